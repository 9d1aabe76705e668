#!/bin/sh
# The runs of docs/results.md's "Generated games: train vs held-out variants" (CPU, 2 shared cores).
# ARCHIVE: `octax-gym generate --family dodger --count 64 --seed 0 --out $ARCHIVE` (39 accepted: 25 train, 14 test).
# OUT: where the runs go. QUEUE: multitask or single (the two queues ran side by side).
set -e
ARCHIVE=${ARCHIVE:-generated/dodger}
OUT=${OUT:-runs/generated-dodger}
# Every agent: the same batch (50 envs x 32 steps, 8 minibatches, the cpu preset's PPO otherwise), the same
# 320,000 env steps, evaluated at the start and the end on 8 episodes per game and policy, each cut at 300
# steps (the horizon the archive's reference and random_horizon scores are measured over).
COMMON="--num-envs 50 --num-steps 32 --num-minibatches 8 --total-steps 320000 --eval-every 0 --eval-envs 8
        --eval-max-steps 300 --no-progress"
if [ "${QUEUE:-multitask}" = multitask ]; then
    # (a) one agent per seed on the 25 train variants (lane i plays variant i mod 25: 2 lanes each), the
    # screen alone (no game one-hot: a held-out variant has none); evaluated on the 14 test variants too.
    octax-gym train multitask --games "archive:$ARCHIVE:train" --eval-games "archive:$ARCHIVE:test" \
        --no-game-input --num-seeds 2 $COMMON --out-dir "$OUT/multitask"
else
    # (b) one agent per variant, seed 0, evaluated on the 38 other accepted variants. Planned: the first,
    # 13th and 25th train variant (archive order), SINGLES="dodger-s0-0000 dodger-s0-0025 dodger-s0-0061";
    # the time this result had (2 shared cores) ran the first alone.
    for game in ${SINGLES:-dodger-s0-0000}; do
        others=$(python -c "import json, sys; a = json.load(open(sys.argv[1] + '/archive.json'));
print(','.join('archive:' + sys.argv[1] + ':' + g['name'] for g in a['games'] if g['accepted'] and g['name'] != sys.argv[2]))" \
            "$ARCHIVE" "$game")
        octax-gym train ppo --games "archive:$ARCHIVE:$game" --eval-games "$others" $COMMON \
            --out-dir "$OUT/single-$game"
    done
fi
