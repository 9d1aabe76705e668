#!/bin/bash
# PPO CPU evidence (issue 40): 4 rapid-plateau games x 2 seeds x 1,048,576 steps, one program; resumable.
cd /work/evidence-tree  # a git worktree: started at fb117a1, moved to b1290a1 (the faster-compiling network, bit-identical: tests/train/test_parts.py)
export OCTAX_ROM_DIR=/work/shared/roms/octax
OUT=/work/cpu-evidence/ppo
ARGS="--preset cpu --games Airplane,Brix,Deep8,Filter --num-seeds 2 --total-steps 1048576 --eval-every 131072 --checkpoint-every 32 --no-progress"
if [ -f $OUT/resume/checkpoint.msgpack ]; then
  exec nice -n 19 /work/main/.venv/bin/python -m octax_gym train ppo --resume $OUT --no-progress
else
  exec nice -n 19 /work/main/.venv/bin/python -m octax_gym train ppo $ARGS --out-dir $OUT
fi
