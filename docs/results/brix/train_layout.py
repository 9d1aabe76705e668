"""`octax-gym train` with the torso in the layout LAYOUT names (see train_layout_torso.py).

    LAYOUT=paper python train_layout.py train ppo --games Brix --seed 0 --preset cpu ...
"""
import sys

import train_layout_torso  # noqa: F401  (swaps the torso when LAYOUT=paper)
from octax_gym.cli import main

sys.exit(main(sys.argv[1:]))
