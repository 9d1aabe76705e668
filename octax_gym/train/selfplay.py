"""Self-play as a configuration of the one loop: PPO (ppo.py) on both seats of a two-player game.

    octax-gym train selfplay --game Cycles --pool 4 --out-dir runs/selfplay/cycles

One network plays both seats of `octax_core.make_multi(game)`: seats.SeatLanes makes each (env,
seat) a lane, so ppo.py's rollout, GAE and loss train on both seats' samples, each seat with its
own rewards, values and advantages, its player plane telling the network which side it plays and
its legal mask (turn-based games) closing every action but no-op to the seat not to move.

The pool (`--pool K`, fictitious-self-play style): the agent's params are snapshotted at every
evaluation's update (a ring of the last K, kept in the runner, so a resumed run has them). Before
each rollout one snapshot is drawn, and each env with probability `pool_prob` has it play one seat
(drawn per env) for that rollout instead of the current params. Those seats' samples were made by
another policy, so their weight in ppo_loss is 0; the env's other seat trains as usual. K = 0 is
pure self-play: the current params on both seats, every sample trains.

The evaluation (`make_evaluate`) plays matches, `octax_core.env.ladder`'s one compiled match: the
agent, greedy (the largest legal logit) and sampled (its policy as trained), against each of
`eval_opponents` (`--eval-opponents`, players of `octax_core.env.players`, weakest first; by default
the ladder's `random`, `eps0.5` and `scripted` rungs, so a run shows the rung it climbs to, not only
the two ends), `eval_envs` games each, half from each seat, each to its end or `eval_max_steps`,
from no-op starts. The network player takes its params as an argument, so one compiled match
serves every evaluation and seed. A game is won when the agent's return (the change of its seat's
score) beats the opponent's. The rows (`eval_columns(config.eval_opponents)`, in progress.csv
where a one-player run has its returns):

* `eval_mean_return`, `eval_greedy_return`: the sampled and greedy agent's mean return against the
  strongest opponent the game has (the last of `eval_opponents` it has).
* `<policy>_vs_<opponent>_<stat>` for policy greedy, sampled, each opponent and stat `win`, `draw`,
  `loss` (fractions of the games) and `margin` (the mean of the agent's return minus the
  opponent's); nan for an opponent the game does not have (a scripted one where it has none).
* `eval_ended_frac`: the fraction of all those games that ended before the step cap.

The Elo of an agent against the game's ladder of fixed rungs is `octax-gym evaluate GAME --agent
OUT/agents/<game>-seed<s>.msgpack --opponents ladder`'s (`octax_core.env.ladder.play_ladder`), run
on a saved agent, not at every evaluation.
"""

from __future__ import annotations

import math
from typing import Any, Callable, NamedTuple

import jax
import jax.numpy as jnp

from octax_core.env import ladder
from octax_core.env.players import Player, check_player, make_player, player_names
from octax_gym.train.config import TrainConfig
from octax_gym.jax_policy import network_player
from octax_gym.train.seats import SEATS, SeatLanes

POLICIES = ("greedy", "sampled")
STATS = ("win", "draw", "loss", "margin")


def eval_columns(opponents) -> tuple[str, ...]:
    """progress.csv's evaluation columns of a run evaluated against `opponents` (the module docstring)."""
    return (("eval_mean_return", "eval_greedy_return")
            + tuple(f"{policy}_vs_{opponent}_{stat}" for opponent in opponents for policy in POLICIES
                    for stat in STATS) + ("eval_ended_frac",))


def open_opponents(opponents, spec) -> list[str]:
    """Those of `opponents` that the game has (a scripted player, and its eps<p> rungs, only where it has one)."""
    def has(name):
        try:
            check_player(name, spec)
        except ValueError:
            return False
        return True
    return [name for name in opponents if has(name)]


class Pool(NamedTuple):
    """The last K snapshots of an agent's params, and how many of the K slots are filled."""

    params: Any  # the params' tree, each leaf (K, ...)
    count: jax.Array  # () int32


def with_pool(config: TrainConfig, init: Callable) -> Callable:
    """`init(key, game)` with an empty pool of `config.pool` slots in the runner (the first
    snapshot is taken before the first rollout)."""
    def init_with_pool(key, game):
        runner = init(key, game)
        stack = jax.tree.map(lambda x: jnp.stack([x] * config.pool), runner.params)
        return runner._replace(pool=Pool(stack, jnp.int32(0)))
    return init_with_pool


def draw_opponent(config: TrainConfig, runner):
    """The runner with its pool refreshed (the current params into the next slot, on an
    evaluation's update) and its key advanced, and the rollout's opponent: a snapshot drawn from
    the pool, and the (2N,) lanes it plays (one seat of each env, with probability `pool_prob`)."""
    pool, update, every = runner.pool, runner.updates, config.eval_interval
    snap = update % every == 0
    slot = (update // every) % config.pool
    stack = jax.tree.map(lambda s, x: s.at[slot].set(jnp.where(snap, x, s[slot])), pool.params, runner.params)
    count = jnp.where(snap, jnp.minimum(pool.count + 1, config.pool), pool.count)
    key, pick_key, env_key, seat_key = jax.random.split(runner.key, 4)
    past_params = jax.tree.map(lambda s: s[jax.random.randint(pick_key, (), 0, count)], stack)
    num_envs = runner.obs.shape[0] // SEATS
    past_env = jax.random.bernoulli(env_key, config.pool_prob, (num_envs,))
    past_seat = jax.random.randint(seat_key, (num_envs,), 0, SEATS)
    past = past_env[:, None] & (jnp.arange(SEATS)[None, :] == past_seat[:, None])  # (N, 2)
    runner = runner._replace(pool=Pool(stack, count), key=key)
    return runner, (past_params, past.reshape(-1))


def evaluation_opponents(lanes: SeatLanes, opponents) -> list[tuple[str, Player]]:
    """(name, player) of each of `opponents` the game has, for the evaluation env: in a mirrored
    one (`--mirror`) the scripted players answer seat 1 in its mirror image (`make_player`'s
    `mirrored`), as the network, which sees and plays it, does."""
    return [(name, make_player(name, lanes.spec, lanes.eval_env.mirrored))
            for name in open_opponents(opponents, lanes.spec)]


def make_evaluate(lanes: SeatLanes, num_games: int, max_steps: int, opponents) -> Callable:
    """`evaluate(params, keys, games) -> [per agent: {(policy, opponent): ladder.MatchResult}]`:
    each agent (`params` stacked along the agent axis, `keys` one per agent) against each of
    `opponents` that the game has, greedy and sampled from the same starts (the same key). One
    match, compiled on first use, plays them all."""
    chosen = evaluation_opponents(lanes, opponents)
    if not chosen:
        raise ValueError(f"selfplay: {lanes.spec.id} has none of the eval_opponents {', '.join(opponents)}; its "
                         f"players: {', '.join(player_names(lanes.spec))}")
    opponents, opponent_players = zip(*chosen)
    players = [network_player(True), network_player(False), *opponent_players]
    match = ladder.make_match(lanes.eval_env, lanes.eval_params, num_games, max_steps, players)

    def evaluate(params, keys, games) -> list[dict]:
        out = []
        for i in range(len(keys)):
            agent = jax.tree.map(lambda x: x[i], params)
            results = {}
            for k, opponent in enumerate(opponents):
                key = jax.random.fold_in(keys[i], k)
                for j, policy in enumerate(POLICIES):
                    results[policy, opponent] = match(j, agent, len(POLICIES) + k, agent, key)
            out.append(results)
        return out

    return evaluate


def evaluation_cells(evaluation: list, i: int, opponents) -> dict:
    """Row `i`'s `eval_columns(opponents)` from `make_evaluate`'s results (see the module docstring)."""
    results = evaluation[i]
    top = [name for name in opponents if ("sampled", name) in results][-1]  # the strongest the game has
    cells = {"eval_mean_return": float(results["sampled", top].return_a.mean()),
             "eval_greedy_return": float(results["greedy", top].return_a.mean())}
    ended = []
    for opponent in opponents:
        for policy in POLICIES:
            record = ladder.record(results[policy, opponent]) if (policy, opponent) in results else {}
            ended += [float(e) for e in results[policy, opponent].ended] if record else []
            for stat in STATS:
                cells[f"{policy}_vs_{opponent}_{stat}"] = record.get(stat, math.nan)
    cells["eval_ended_frac"] = sum(ended) / len(ended)
    return cells
