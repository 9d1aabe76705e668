"""One torch thread for a test module's tiny networks: `from torch_threads import one_torch_thread`.

On a busy 2-core machine torch's thread pool makes each call of a small network 30-100x slower
(its threads wait for cores the pytest workers hold), so modules that run such networks take this
autouse fixture; the thread count is restored after each test."""

import pytest


@pytest.fixture(autouse=True)
def one_torch_thread():
    import torch

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)
