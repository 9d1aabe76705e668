#!/usr/bin/env bash
# The paper's table in one program, for a GPU machine: PPO with the paper preset (512 envs x 32
# steps, 4 epochs x 32 minibatches, Adam 5e-4, 5M steps an agent) on the paper's 16 games x 3
# seeds = 48 agents, one compiled program (octax-gym train, docs/training.md). Prints the env
# steps/s of all agents together, and leaves OUT/paper-ppo/{progress.csv,learning_curve.png,
# summary.json,agents/}.
#
#   OUT=/tmp/out benchmarks/train_gpu.sh                  # the full run (5M steps x 48 agents)
#   OUT=/tmp/out STEPS=1048576 SEEDS=2 benchmarks/train_gpu.sh   # shorter, where time is short
#   OUT=/tmp/out GAMES=Pong,Brix STEPS=262144 benchmarks/train_gpu.sh   # a smoke run
#
# Settings (environment variables): OUT (required), ALGO (ppo), GAMES (octax16), SEEDS (3),
# STEPS (per agent; default the preset's 5,000,000), EVAL_EVERY (the preset's 131,072),
# CHECKPOINT_EVERY (updates between resumable checkpoints; 20). A run cut short keeps its rows and
# agents up to its last evaluation; `octax-gym train ppo --resume $OUT/paper-ppo` continues it.
set -euo pipefail
: "${OUT:?set OUT to the output folder}"
ALGO="${ALGO:-ppo}"
GAMES="${GAMES:-octax16}"
SEEDS="${SEEDS:-3}"
CHECKPOINT_EVERY="${CHECKPOINT_EVERY:-20}"
RUN="$OUT/paper-$ALGO"
args=(train "$ALGO" --preset paper --games "$GAMES" --num-seeds "$SEEDS" --out-dir "$RUN"
      --checkpoint-every "$CHECKPOINT_EVERY" --no-progress)
[[ -n "${STEPS:-}" ]] && args+=(--total-steps "$STEPS")
[[ -n "${EVAL_EVERY:-}" ]] && args+=(--eval-every "$EVAL_EVERY")
python -c "import jax; print('devices:', jax.devices())"
start=$(date +%s)
if [[ -f "$RUN/resume/checkpoint.json" ]]; then
    python -m octax_gym train "$ALGO" --resume "$RUN" --no-progress
else
    python -m octax_gym "${args[@]}"
fi
echo "wall: $(( $(date +%s) - start )) s"
python - "$RUN" <<'PY'
import json, sys
summary = json.load(open(f"{sys.argv[1]}/summary.json"))
print(f"env steps/s of all agents together: {summary['env_steps_per_s']:,.0f} "
      f"(training {summary['train_s']:.0f} s; compile and evaluation excluded)")
PY
