"""Many seeds in one program (examples/jax_training.py): agent i of a `--num-seeds S` run learns what
a run of seed `seed + i` alone learns, for both JAX examples, and writes one CSV row per seed."""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import jax
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))
import jax_training  # noqa: E402
import train_jax_ppo as ppo  # noqa: E402
import train_jax_pqn as pqn  # noqa: E402

from counter_game import COUNTER  # noqa: E402

SETTINGS = dict(num_envs=6, num_steps=8, num_minibatches=2, update_epochs=2, total_steps=6 * 8 * 4,
                eval_every=96, eval_envs=5, env_overrides=(("max_episode_steps", 12),))


@pytest.mark.slow  # a long check (>20 s on 2 cores); CI's test-slow runs it
@pytest.mark.parametrize("algorithm", [ppo, pqn], ids=["ppo", "pqn"])
def test_each_seed_of_a_batched_run_learns_what_it_learns_alone(algorithm, counter_rom, tmp_path):
    together = algorithm.train(algorithm.Config(seed=10, num_seeds=3, **SETTINGS), tmp_path / "together",
                               game=COUNTER, rom=counter_rom, progress=False)
    alone = algorithm.train(algorithm.Config(seed=11, **SETTINGS), tmp_path / "alone",
                            game=COUNTER, rom=counter_rom, progress=False)
    # Seed 11 is the second agent of the batched run.
    params = jax.tree.map(lambda x: x[1], together["final_params"])
    flat_together, flat_alone = jax.tree.leaves(params), jax.tree.leaves(alone["final_params"])
    assert len(flat_together) == len(flat_alone)
    for a, b in zip(flat_together, flat_alone):
        np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-5)
    rows_together = [r for r in together["rows"] if r["seed"] == 11]
    assert [r["step"] for r in rows_together] == [r["step"] for r in alone["rows"]] == [0, 96, 192]
    for mine, theirs in zip(rows_together, alone["rows"]):
        for name in ("eval_mean_return", "eval_std", "random_mean_return", "train_episodes"):
            assert mine[name] == pytest.approx(theirs[name], rel=1e-6), name
    # The other seeds learnt something else: they are not copies of one agent.
    others = [jax.tree.leaves(jax.tree.map(lambda x, i=i: x[i], together["final_params"]))[0] for i in (0, 2)]
    assert not np.allclose(others[0], flat_alone[0]) and not np.allclose(others[1], flat_alone[0])
    with open(together["csv"]) as f:
        assert [int(r["seed"]) for r in csv.DictReader(f)] == [10, 11, 12] * 3


def test_over_seeds_maps_a_function_and_keeps_one_seed_unmapped():
    calls = []

    def fn(x, y):
        calls.append(x.shape)
        return x * 2 + y

    x = np.arange(6.0).reshape(3, 2)
    np.testing.assert_array_equal(jax_training.over_seeds(fn, 3)(x, x), x * 3)
    one = jax_training.over_seeds(fn, 1, in_axes=(0, None))(x[:1], np.ones(2))
    np.testing.assert_array_equal(one, x[:1] * 2 + 1)
    assert calls[-1] == (2,)  # the lone seed's slice, not a mapped axis of 1


def test_seed_keys_are_those_a_lone_run_makes():
    config = ppo.Config(seed=3, num_seeds=2)
    train_keys, eval_keys, random_keys = jax_training.seed_keys(config)
    for i, seed in enumerate((3, 4)):
        expected = jax.random.split(jax.random.key(seed), 3)
        for keys, j in ((train_keys, 0), (eval_keys, 1), (random_keys, 2)):
            assert np.array_equal(jax.random.key_data(keys[i]), jax.random.key_data(expected[j]))


def test_any_over_seeds_is_shared_by_the_mapped_seeds_so_a_cond_stays_a_branch():
    flags = np.array([[False, False], [False, True], [False, False]])
    shared = jax_training.over_seeds(lambda f: jax_training.any_over_seeds(f, 3), 3)(flags)
    assert shared.tolist() == [True, True, True]  # seed 1's truncation is every seed's predicate
    alone = jax_training.over_seeds(lambda f: jax_training.any_over_seeds(f, 1), 1)(flags[1:2])
    assert alone.tolist() == [True]

    def step(f):
        return jax.lax.cond(jax_training.any_over_seeds(f, 3), lambda: f.sum(), lambda: -1)

    jaxpr = str(jax.make_jaxpr(jax_training.over_seeds(step, 3))(flags))
    assert "cond[" in jaxpr and "select_n" not in jaxpr  # with a per-seed predicate vmap makes it a select
    per_seed = str(jax.make_jaxpr(jax.vmap(lambda f: jax.lax.cond(f.any(), lambda: f.sum(), lambda: -1)))(flags))
    assert "select_n" in per_seed
