#!/bin/bash
# PQN CPU evidence (issue 40): 4 rapid-plateau games x 2 seeds x 1,048,576 steps, one program; resumable. Evaluations every 262,144 steps: on this CPU one evaluation (32 sampled + 32 greedy episodes an agent, each to its end or 4,500 steps) costs about half as much as 131,072 training steps
cd /work/evidence-tree  # a git worktree: started at fb117a1, moved to b1290a1 (the faster-compiling network, bit-identical: tests/train/test_parts.py)
export OCTAX_ROM_DIR=/work/shared/roms/octax
OUT=/work/cpu-evidence/pqn
ARGS="--preset cpu --games Airplane,Brix,Deep8,Filter --num-seeds 2 --total-steps 1048576 --eval-every 262144 --checkpoint-every 32 --no-progress"
if [ -f $OUT/resume/checkpoint.msgpack ]; then
  exec nice -n 19 /work/main/.venv/bin/python -m octax_gym train pqn --resume $OUT --no-progress
else
  exec nice -n 19 /work/main/.venv/bin/python -m octax_gym train pqn $ARGS --out-dir $OUT
fi
