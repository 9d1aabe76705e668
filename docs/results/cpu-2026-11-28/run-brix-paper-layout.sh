#!/bin/bash
# Brix with the paper's network layout (issue 40): PPO, 2 seeds x 524,288 steps, one program; resumable.
cd /work/layout-tree  # a git worktree at 2d92449 (--network-layout)
export OCTAX_ROM_DIR=/work/shared/roms/octax
OUT=/work/cpu-evidence/brix-paper
ARGS="--preset cpu --games Brix --num-seeds 2 --network-layout paper --total-steps 524288 --eval-every 131072 --checkpoint-every 32 --no-progress"
if [ -f $OUT/resume/checkpoint.msgpack ]; then
  exec /work/main/.venv/bin/python -m octax_gym train ppo --resume $OUT --no-progress
else
  exec /work/main/.venv/bin/python -m octax_gym train ppo $ARGS --out-dir $OUT
fi
