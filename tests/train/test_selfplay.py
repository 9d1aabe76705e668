"""Self-play, the trainer's `selfplay` configuration, on the tiny two-player test games
(tests/two_player_games.py): TwoCounters (simultaneous, with a scripted player) trains a TINY
run (with a pool, the rate and the entropy weight annealed, evaluated against three rungs);
TakeTurns (turn-based) checks that the rollout takes its legal masks from the env's state, in the
first rollout of a pool trainer that the pool's checks read too."""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

pytest.importorskip("flax")
from two_player_games import TAKE_TURNS, TWO_COUNTERS  # noqa: E402

from octax_gym.train import preset, selfplay, train  # noqa: E402
from octax_gym.train.algorithm import make_trainer  # noqa: E402
from octax_gym.train.seats import SeatLanes  # noqa: E402

# tiny_run.TINY's settings as a config (TINY is flags; the test games are GameSpecs, not ids)
TINY = dict(num_envs=4, num_steps=8, num_minibatches=2, update_epochs=1, total_steps=192, eval_every=64,
            eval_envs=2, eval_max_steps=30, env_overrides=(("max_episode_steps", 20),), checkpoint_every=2)
STEPS = [0, 64, 128, 192]


def tiny(**overrides):
    return preset("cpu", "selfplay", games=(TWO_COUNTERS,), **{**TINY, **overrides})


# The checks share their programs (compiling them is what this module pays for): one run with a pool
# and its same-seed repeat (`runs`), one pool trainer's first rollout on the turn-based game
# (`pooled`: the pool's checks are a seat's, whichever game; the masks' are the turn-based game's).
POOLED = dict(pool=2, pool_prob=1.0)


@pytest.fixture(scope="module")
def runs(two_counters_rom, tmp_path_factory):
    """A TINY run with a pool of past selves, and the same run again (the same seed), each in its folder."""
    config = tiny(save_at_evals=True, pool=2, anneal_lr=True, ent_coef_final=0.002)
    return [train(config, tmp_path_factory.mktemp("selfplay") / "run", roms=[two_counters_rom], progress=False)
            for _ in range(2)]


@pytest.fixture(scope="module")
def run(runs):
    return runs[0]


def test_a_row_per_evaluation_with_the_matches_columns(run):
    rows = run["rows"]
    assert [r["step"] for r in rows] == STEPS and {r["game"] for r in rows} == {"TwoCounters"}
    header = run["csv"].read_text().splitlines()[0].split(",")
    opponents = ("random", "eps0.5", "scripted")  # the default: the ladder's ends and a rung between
    assert all(column in header for column in selfplay.eval_columns(opponents)) and "normalized_score" not in header
    for row in rows:
        for policy in selfplay.POLICIES:
            for opponent in opponents:  # TwoCounters has a scripted player (and so eps0.5): every cell is a number
                rates = [row[f"{policy}_vs_{opponent}_{stat}"] for stat in ("win", "draw", "loss")]
                assert math.isclose(sum(rates), 1.0) and all(0 <= r <= 1 for r in rates)
        # the scripted player holds its 2-key: against it an agent's return is its own count, the margin below it
        assert row["eval_mean_return"] - row["sampled_vs_scripted_margin"] >= 0


def test_the_rate_and_the_entropy_weight_decay_linearly_over_the_run(run):
    # 6 updates; the rows are evaluations at updates 0, 2, 4, 6: the weight during the update after each
    np.testing.assert_allclose([r["learning_rate"] for r in run["rows"]], [5e-4 * (1 - u / 6) for u in (0, 2, 4, 6)])
    np.testing.assert_allclose([r["ent_coef"] for r in run["rows"]],
                               [0.01 + (0.002 - 0.01) * u / 6 for u in (0, 2, 4, 6)], rtol=1e-6)


def test_the_loss_takes_the_updates_entropy_weight_from_the_batch(pooled, first_losses):
    """With ent_coef_final the batch ends with the update's weight, and the loss uses it, not ent_coef."""
    config = pooled[0]
    (plain, stats), annealed = first_losses["plain"], first_losses["annealed"]
    np.testing.assert_allclose(annealed - plain, (config.ent_coef - 0.004) * stats["entropy"], rtol=1e-4)


def test_the_entropy_weight_is_constant_without_ent_coef_final():
    config = tiny()
    assert config.ent_coef_final is None and config.ent_coef_at(3) == config.ent_coef == 0.01
    config = tiny(ent_coef_final=0.0)
    ends = [config.ent_coef_at(u) for u in (0, config.num_updates // 2, config.num_updates, 10 * config.num_updates)]
    np.testing.assert_allclose(ends, [0.01, 0.005, 0.0, 0.0], rtol=1e-6)  # past the end: the final weight


def test_a_game_without_a_scripted_player_is_evaluated_against_the_opponents_it_has():
    from octax_core.env.games import get_spec

    opponents = ("random", "eps0.5", "scripted")
    assert selfplay.open_opponents(opponents, get_spec("SpaceRacer")) == ["random"]
    assert selfplay.open_opponents(opponents, TWO_COUNTERS) == list(opponents)
    assert "greedy_vs_eps0.25_margin" in selfplay.eval_columns(("random", "eps0.25"))


def test_mirror_makes_both_envs_mirrored_and_the_scripted_opponent_answers_in_the_mirror_image(two_counters_rom):
    from types import SimpleNamespace

    seats = dataclasses.replace(TWO_COUNTERS.seats, mirror="left-right", mirror_actions=(0, 2, 1))
    mirrored = dataclasses.replace(TWO_COUNTERS, seats=seats)
    config = dataclasses.replace(tiny(), games=(mirrored,), env_overrides=TINY["env_overrides"] + (("mirror", True),))
    config.check()
    lanes = SeatLanes(config.games, dict(config.env_overrides), roms=[two_counters_rom])
    plain = SeatLanes((mirrored,), dict(TINY["env_overrides"]), roms=[two_counters_rom])
    assert lanes.env.mirrored and lanes.eval_env.mirrored and not plain.eval_env.mirrored
    state = SimpleNamespace(machine=None)  # TwoCounters' bot holds its key 2 whatever the machine
    answers = [[int(player(None, jax.random.key(0), None, state, seat, None)) for seat in (0, 1)]
               for ours in (lanes, plain) for name, player in selfplay.evaluation_opponents(ours, ("scripted",))]
    assert answers == [[2, 1], [2, 2]]  # seat 1's key 2 is its mirror image's action 1


def test_params_change_and_agents_are_saved_as_the_loop_saves_them(run):
    from octax_gym import jax_policy
    from octax_gym.play.agents import load_agent

    folder = run["out_dir"] / "agents"
    first, last = (jax_policy.load_params(folder / f"TwoCounters-seed0{s}.msgpack") for s in ("-step0", ""))
    assert any(not np.array_equal(a, b) for a, b in zip(jax.tree.leaves(first), jax.tree.leaves(last)))
    assert jax_policy.describe(last).channels == 5  # 4 frames and the player plane
    agent = load_agent(folder / "TwoCounters-seed0.msgpack", num_actions=3)  # octax-gym play's loader
    assert agent(np.zeros((5, 32, 64), np.uint8)) in (0, 1, 2)


def test_the_same_seed_gives_the_same_run(runs):
    timing = ("wall_s", "env_steps_per_s")
    first, again = ([{k: v for k, v in r.items() if k not in timing} for r in run["rows"]] for run in runs)
    assert again == first
    for a, b in zip(jax.tree.leaves(runs[1]["final_params"]), jax.tree.leaves(runs[0]["final_params"])):
        np.testing.assert_array_equal(a, b)


@pytest.fixture(scope="module")
def pooled(take_turns_rom):
    """A pool trainer of TakeTurns (2 past selves, one on a seat of every env): its config, lanes,
    trainer, first runner, first rollout's (runner, batch, totals), and, from the first runner,
    the pool after each of 5 draws at updates 0..4 (params + update at update `update`) with the
    pool's count after each; all in one program."""
    config = dataclasses.replace(tiny(**POOLED), games=(TAKE_TURNS,))
    lanes = SeatLanes((TAKE_TURNS,), dict(config.env_overrides), roms=[take_turns_rom])
    trainer = make_trainer(config, lanes)

    @jax.jit
    def first(key):
        runner = trainer.init(key, jnp.int32(0))
        drawn, counts = runner, []
        for update in range(5):  # eval_interval = 2 updates: snapshots at updates 0, 2, 4 into a ring of 2
            drawn = selfplay.draw_opponent(config, drawn._replace(
                updates=jnp.int32(update), params=jax.tree.map(lambda x: x + update, drawn.params)))[0]
            counts.append(drawn.pool.count)
        return runner, trainer.collect(runner), (drawn.pool, jnp.stack(counts))

    return (config, lanes, trainer, *first(jax.random.key(0)))


@pytest.fixture(scope="module")
def first_losses(pooled):
    """ppo_loss on the pooled trainer's first batch (flattened), in one program: the loss and its
    statistics; the loss with an entropy weight of 0.004 ending the batch (ent_coef_final's form);
    its gradient, and its gradient on the batch with every weight-0 sample's action and advantage
    changed."""
    from octax_gym.train.networks import masked
    from octax_gym.train.ppo import ppo_loss

    config, _, trainer, _, (after, batch, _), _ = pooled

    def apply(params, obs, game, legal):
        logits, value = trainer.network.apply(params, obs)
        return masked(logits, legal), value

    @jax.jit
    def losses(params, flat):
        zero = flat[-1] == 0
        changed = list(flat)
        changed[3] = jnp.where(zero, 1 - flat[3], flat[3])  # actions (TakeTurns': no-op and its key)
        changed[6] = jnp.where(zero, flat[6] + 100.0, flat[6])  # advantages
        grad = jax.grad(lambda p, minibatch: ppo_loss(p, apply, config, minibatch)[0])
        return {"plain": ppo_loss(params, apply, config, flat),
                "annealed": ppo_loss(params, apply, config, flat + (jnp.full(flat[3].shape, 0.004, jnp.float32),))[0],
                "grad": grad(params, flat), "grad_changed": grad(params, tuple(changed))}

    return losses(after.params, tuple(jax.tree.map(lambda x: x.reshape((-1,) + x.shape[2:]), batch)))


def test_a_past_self_plays_one_seat_of_an_env_and_its_samples_weigh_zero(pooled, first_losses):
    config, _, _, _, (after, batch, _), _ = pooled
    weight = np.asarray(batch[-1]).reshape(config.num_steps, config.num_envs, 2)
    # every env (pool_prob 1): one seat, the same for the whole rollout, played by the past self
    assert (weight.sum(-1) == 1).all() and (weight == weight[:1]).all()
    assert int(after.pool.count) == 1  # the first rollout's snapshot: the initial params
    # A weight-0 sample trains nothing: whatever its action and advantage, the same gradient.
    for a, b in zip(jax.tree.leaves(first_losses["grad"]), jax.tree.leaves(first_losses["grad_changed"])):
        np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-7)


def test_the_pool_takes_a_snapshot_at_each_evaluations_update(pooled):
    _, _, _, start, _, (pool, counts) = pooled
    assert np.asarray(counts).tolist() == [1, 1, 2, 2, 2]
    leaf = lambda tree: np.asarray(jax.tree.leaves(tree)[0])  # noqa: E731
    base = leaf(start.params)
    # slot 0 holds update 4's params (base + 0+1+2+3+4), slot 1 update 2's (base + 0+1+2)
    np.testing.assert_allclose(leaf(pool.params)[0], base + 10, rtol=1e-6)
    np.testing.assert_allclose(leaf(pool.params)[1], base + 3, rtol=1e-6)


def test_turn_based_legal_masks_come_from_the_state_and_are_honoured(pooled):
    config, lanes, _, runner, (_, batch, _), _ = pooled
    legal, action = np.asarray(batch[2]), np.asarray(batch[3])  # (T, 2N, ACTIONS), (T, 2N)
    assert np.take_along_axis(legal, action[..., None], -1).all()  # never a closed action (the past self's neither)
    per_env = legal.reshape(config.num_steps, config.num_envs, 2, -1)
    # one seat moves: it has its key (action 1), the other no-op alone; actions past the game's 2 never
    assert (per_env[..., 1].sum(-1) == 1).all() and not per_env[..., 2:].any()
    assert (per_env[..., 0]).all()
    # the masks are the env's own
    expected = jax.vmap(lanes.env.legal_action_mask)(runner.env_state).reshape(2 * config.num_envs, -1)
    np.testing.assert_array_equal(legal[0, :, :2], expected)


@pytest.mark.parametrize("flags, message", [
    (["selfplay", "--game", "Airplane"], "selfplay: Airplane is a one-player game; two-player games: Cycles"),
    (["selfplay", "--games", "Cycles,Duel"], "selfplay trains on one two-player game; got games Cycles, Duel"),
    (["selfplay", "--game", "Cycles", "--eval-envs", "3"], "eval_envs = 3 must be even"),
    (["selfplay", "--game", "Cycles", "--pool-prob", "2"], "pool_prob must be in [0, 1], got 2.0"),
    (["selfplay", "--game", "Cycles", "--pool", "-1"], "pool must be an int >= 0, got -1"),
    (["ppo", "--game", "Airplane", "--pool", "2"], "--pool: not a setting of ppo (of selfplay)"),
    (["selfplay", "--game", "Cycles", "--eval-opponents", "random,best"], "unknown player 'best'; valid: 'random', "
                                                                          "'noop', 'scripted', or 'eps<p>'"),
    (["selfplay", "--game", "Cycles", "--eval-opponents", "random,random"], "eval_opponents names a player twice"),
    (["selfplay", "--game", "Cycles", "--eval-opponents", "eps2"], "the eps of 'eps2' must be"),
    (["ppo", "--game", "Airplane", "--eval-opponents", "random"], "--eval-opponents: not a setting of ppo (of "
                                                                  "selfplay)"),
    (["selfplay", "--game", "Cycles", "--ent-coef-final", "-0.1"], "ent_coef_final must be >= 0, got -0.1"),
    (["pqn", "--game", "Airplane", "--ent-coef-final", "0.001"], "--ent-coef-final: not a setting of pqn"),
    (["selfplay", "--game", "Duel", "--mirror"], "selfplay: Duel has no mirrored seats (Seats.mirror); mirror is "
                                                 "for Cycles"),
    (["ppo", "--game", "Airplane", "--mirror"], "mirror is a setting of selfplay (a two-player game's seats), not of "
                                                "ppo"),
])
def test_bad_selfplay_flags_are_refused_by_name(flags, message, capsys, tmp_path, monkeypatch):
    from octax_gym.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["train", *flags, "--no-progress"]) == 1
    assert message in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_the_presets_have_selfplay():
    for name in ("cpu", "paper"):
        config = preset(name, "selfplay", games=("Cycles",), pool=4)
        assert config.selfplay and config.pool == 4 and config.clip_eps == preset(name, "ppo").clip_eps
        assert config.num_envs == preset(name, "ppo").num_envs


@pytest.mark.slow
def test_the_cli_trains_cycles_and_play_loads_its_agent(tmp_path):
    """`octax-gym train selfplay --game Cycles` end to end (a real game: its compile is the minute)."""
    from octax_gym.cli import main
    from octax_gym.play.agents import load_agent
    from tiny_run import TINY as FLAGS

    out = tmp_path / "run"
    assert main(["train", "selfplay", "--game", "Cycles", "--pool", "2", *FLAGS, "--out-dir", str(out)]) == 0
    lines = (out / "progress.csv").read_text().splitlines()
    assert len(lines) == 1 + 4 and "greedy_vs_scripted_win" in lines[0]
    agent = load_agent(out / "agents" / "Cycles-seed0.msgpack", num_actions=5)
    assert agent(np.zeros((5, 32, 64), np.uint8)) in range(5)
