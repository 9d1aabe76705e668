"""Every test in this folder plays archive games for hundreds of steps, some at 1,000 instructions
per frame: together they take longer than the rest of the suite, so they are all marked `slow`.
`make test` leaves them out; `make test-slow` (and CI, `.ci/run`) runs them.
"""

import pytest


def pytest_collection_modifyitems(config, items):
    here = __file__.rsplit("/", 1)[0]
    for item in items:
        if str(item.path).startswith(here):
            item.add_marker(pytest.mark.slow)
