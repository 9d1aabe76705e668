# Second GPU call: PQN, paper preset, the rapid-plateau games x 2 seeds, 1M steps an agent.
set -u
export PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_PREALLOCATE=false
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --target /tmp/site .whl/*.whl && export PYTHONPATH=/tmp/site
cd .gpu
export OCTAX_ROM_DIR=$PWD/octax-roms
timeout ${TRAIN_S:-185} python3 -m octax_gym train pqn --preset paper --games Airplane,Brix,Deep8,Filter,Blinky --num-seeds 2 \
  --total-steps 1048576 --eval-every 262144 --eval-envs 64 --out-dir /tmp/pqn --no-progress > $OUT/train.log 2>&1
echo "train exit $?" >> $OUT/train.log
python3 pack.py /tmp/pqn $OUT >> $OUT/train.log 2>&1
