# make demo   the games table, a random agent's steps/s on Pong, and a video of it (demo-pong.mp4)
# make test   run the test suite (all but the tests marked slow), then name the 15 slowest: on 2 cores
#             9 to 15 minutes the first time (520-890 s), about 4 to 8 once JAX's compilation cache (.cache/jax) is
#             warm (234-472 s); the spread is the machine's speed (docs/machine-log.md)
# make test-slow  the slow tests: every archive game played, long ROM runs (CI runs both)
# make bench  throughput of the core on Pong, against the octax package (benchmarks/README.md)
# make bench-scaling  the scaling figure: octax-gym, octax, EnvPool and ale-py Pong against N (docs/scaling.md)
# make wheel-check  the wheel in a clean venv, offline, empty HOME: every archive game builds and passes check_env
# make dataset-suite  train the six suite policies (PPO, all in one program), then collect octax/<Game>/{random,medium,expert}-v0 (docs/datasets.md)
# make roms   rebuild our own games, roms/*.ch8, from their Octo source roms/*.8o
#
# Each target creates .venv when it is missing and installs what it needs into it once: a stamp
# file per extra (.venv/.installed-<extra>) is redone only when pyproject.toml changes.

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
PIP    := $(PY) -m pip

# Only this torch is a local CPU wheel here; an unpinned torch pulls gigabytes of CUDA packages,
# so it goes in first, before any extra that depends on torch gets to pick one.
TORCH        := torch==2.13.0
TORCH_EXTRAS := torch sb3 torchrl all

# Third-party ROMs are never committed. Tests and benchmarks read the octax suite's ROMs from
# ../shared when it is there; on any other machine `roms-ready` fetches them from PyPI, once,
# into the user data folder (hash-verified by the ROM store), where the store finds them.
export OCTAX_ROM_DIR ?= ../shared/roms/octax

# Two pytest workers: JAX compiles are CPU-bound and mostly single-threaded, and on 2 cores this cut
# the suite from ~50 s to ~35 s. loadfile keeps a file's tests, which share compiled functions, in
# one worker. `make test PYTEST_ARGS=` runs serially; `make bench BENCH_ARGS=--quick` is a smoke test.
PYTEST_ARGS ?= -n 2 --dist loadfile
BENCH_ARGS  ?=

# Every game's ROM present and verified, or the octax wheel's ROMs installed from PyPI: no network
# when they are all there already (a hash check of a few dozen small files).
ROMS_READY := $(PY) -m octax_gym roms install --if-missing

.PHONY: help demo test test-slow wheel-check bench bench-scaling dataset-suite roms clean

help:
	@sed -n 's/^# \(make .*\)/\1/p' Makefile

demo: $(VENV)/.installed-video
	$(ROMS_READY)
	$(PY) -m octax_gym.demo

# The slowest tests are named at the end of every run, so that a regression of the suite's time is seen.
test: $(VENV)/.installed-all
	$(ROMS_READY)
	$(PY) -m pytest $(PYTEST_ARGS) -m "not slow" --durations=15

test-slow: $(VENV)/.installed-all
	$(ROMS_READY)
	$(PY) -m pytest $(PYTEST_ARGS) -m slow

wheel-check:
	bash .ci/wheel-check

bench: $(VENV)/.installed-dev
	$(ROMS_READY)
	$(PY) benchmarks/throughput.py $(BENCH_ARGS)

bench-scaling: $(VENV)/.installed-dev $(VENV)/.installed-scaling
	$(ROMS_READY)
	$(PY) benchmarks/scaling.py $(BENCH_ARGS)

# The dataset suite (docs/datasets.md): one `octax-gym train ppo` run of the games (an agent each, one
# program) with every evaluation's agents kept (the medium policies come from them), then `octax-gym
# dataset suite`. A finished run (its summary.json exists) is not trained again, a cut one is resumed
# from its checkpoint; delete runs/suite to retrain.
SUITE_GAMES ?= Airplane Deep8 Dodge Filter Flak Squash
SUITE_RUNS  ?= runs/suite

dataset-suite: $(VENV)/.installed-all
	$(ROMS_READY)
	if [ -f $(SUITE_RUNS)/summary.json ]; then :; \
	elif [ -f $(SUITE_RUNS)/resume/checkpoint.json ]; then $(PY) -m octax_gym train ppo --resume $(SUITE_RUNS) --no-progress; \
	else $(PY) -m octax_gym train ppo --games $(shell echo $(SUITE_GAMES) | tr ' ' ,) --num-envs 64 --num-steps 32 \
	  --num-minibatches 8 --total-steps 262144 --eval-every 65536 --eval-envs 32 --eval-max-steps 2000 \
	  --checkpoint-every 16 --save-at-evals --no-progress --out-dir $(SUITE_RUNS); fi
	$(PY) -m octax_gym dataset suite --runs $(SUITE_RUNS) --games $(SUITE_GAMES) $(SUITE_ARGS)

# tests/core/test_own_roms.py checks that the committed ROMs are what this builds; a game's
# GameSpec names its ROM's SHA-1, so update it after a rebuild that changes the bytes.
roms: $(VENV)/.installed-core
	for source in roms/*.8o; do $(PY) -m octax_gym asm $$source || exit 1; done

$(PY):
	$(PYTHON) -m venv $(VENV)

# .installed-core installs the package alone; .installed-<extra> installs it with that extra.
$(VENV)/.installed-%: pyproject.toml | $(PY)
	$(if $(filter $*,$(TORCH_EXTRAS)),$(PY) -c "import torch" 2>/dev/null || $(PIP) install "$(TORCH)")
	$(PIP) install -e "$(if $(filter core,$*),.,.[$*])"
	touch $@

clean:
	rm -rf build dist *.egg-info .pytest_cache .hypothesis
	find . -path ./$(VENV) -prune -o -name __pycache__ -type d -exec rm -rf {} +
