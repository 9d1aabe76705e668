# One GPU call: the paper preset on the octax16 games x 3 seeds, as far as the time allows.
set -u
export PYTHONUNBUFFERED=1 XLA_PYTHON_CLIENT_PREALLOCATE=false
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --target /tmp/site .whl/*.whl && export PYTHONPATH=/tmp/site
cd .gpu
export OCTAX_ROM_DIR=$PWD/octax-roms
{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv
  python3 -c "import jax, flax, optax, gymnasium; print('jax', jax.__version__, 'flax', flax.__version__, 'optax', optax.__version__, jax.devices())"
  nproc; } > $OUT/env.log 2>&1
timeout ${TRAIN_S:-470} python3 -m octax_gym train ppo --preset paper --games octax16 --num-seeds ${SEEDS:-3} \
  --eval-every ${EVAL_EVERY:-524288} --out-dir /tmp/paper --no-progress > $OUT/train.log 2>&1
echo "train exit $?" >> $OUT/train.log
python3 pack.py /tmp/paper $OUT >> $OUT/train.log 2>&1
ls -la $OUT /tmp/paper >> $OUT/train.log
