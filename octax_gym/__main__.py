"""`python -m octax_gym ...` runs the `octax-gym` command line."""

import sys

from octax_gym.cli import main

sys.exit(main())
