"""Throughput of the CHIP-8 core on Pong, and of the `octax` package on the same work.

A thin script over `octax_gym.bench` (also `octax-gym bench`, which adds a progress bar): each N
prints free-form lines, then exactly one summary line starting with ``BENCH throughput``.

    python benchmarks/throughput.py                    # N = 1, 64, 512, 2048, 8192, with octax
    python benchmarks/throughput.py --quick            # N = 64, 512, 2 repeats (smoke test)
    python benchmarks/throughput.py --envs 512 --devices 2 --no-octax
    python benchmarks/throughput.py --mode env         # the functional env API: obs and reward too
    python benchmarks/throughput.py --mode gym --backend torch   # gym.make_vec, stepped from Python

See benchmarks/README.md for what each field means.
"""

import sys

from octax_gym.bench import main

if __name__ == "__main__":
    sys.exit(main())
