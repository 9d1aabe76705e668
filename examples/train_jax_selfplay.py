"""Self-play PPO on a two-player octax game, end to end in JAX: one network plays both seats.

    python examples/train_jax_selfplay.py --game Duel --num-envs 32 --total-steps 163840 --out-dir runs/selfplay/duel
    python examples/train_jax_selfplay.py --game Duel --pool 4 ...   # past selves as opponents (FSP-style)

The learner is the PPO example's (examples/train_jax_ppo.py: its network, its GAE, its settings),
built from the same shared pieces (examples/jax_update.py: the optimizer and the minibatch epochs;
examples/jax_training.py: the command line). What is self-play's is here:

- The env is `octax_core.make_multi(game)`, N copies vmapped; each step the network reads both
  seats' observations (each carries its player plane: 0 for seat 0, `obs_scale` for seat 1, so the
  one policy knows which side it plays) and acts for both. Both seats' transitions train it: a
  rollout of T steps is 2 x N x T samples, each seat with its own rewards, values and GAE.
- Turn-based games: the logits are masked with `legal_action_mask` (the seat not to move has only
  no-op), when acting and in the loss.
- `--pool K` (fictitious-self-play style): every evaluation also saves a snapshot of the params,
  and the last K snapshots form a pool. At each update one snapshot is drawn from the pool, and
  each env, with probability `--pool-prob`, plays it on one seat (drawn per env) for that rollout
  instead of the current params. Those seats' transitions are not the learner's (another policy
  made them), so they are left out of the loss (weight 0); the learner's seat still trains.
  K = 0 (the default) is pure self-play: the current params on both seats, every sample trains.
- Evaluation every `--eval-every` env steps: the current policy (actions *sampled* from it, as
  the PPO example evaluates; `--eval-greedy` takes the argmax) plays `--eval-envs` games against
  (a) a uniform random player and (b) the game's scripted player (`Seats.scripted_policy`, where
  the game has one), half of them from seat 0 and half from seat 1. A game is played to its end or
  `--eval-max-steps`; it is won if the agent's return (the change of its seat's score) is higher
  than the opponent's at that point, drawn if equal. That reads the same for zero-sum games (Duel:
  return = own points - other's) and for the others (SpaceRacer: crossings of each ship).
  Logged: win rate, draw rate, mean return difference (agent - opponent), fraction of games ended.
- Checkpoints: the params at every evaluation, `checkpoints/params-u<update>.msgpack`
  (flax.serialization), the last also as `params.msgpack`.
- An Elo table at the end (`elo.csv`, printed): a round robin of `--elo-games` games for every
  pair of players (every checkpoint, uniform random, and the scripted player where there is one),
  half from each seat, each to its end or `--elo-max-steps`. Ratings are a fitted Bradley-Terry
  model (maximum likelihood by Hunter's MM iterations, a draw counting half a win to each side,
  plus one virtual draw per pair so that a perfect record stays finite), put on the Elo scale
  (400 log10 of the strength) with the uniform random player at 0.

Writes `progress.csv` (one row per evaluation: update, env steps, each seat's mean training
return, the win rates and return differences, the PPO losses), `learning_curve.png`, the
checkpoints, `elo.csv` and `config.json` to `--out-dir`. One seed per run (no `--num-seeds`).
See docs/results.md, "Self-play".
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import sys
import time
from pathlib import Path
from typing import Any, Callable, NamedTuple, Optional, Sequence

import flax.serialization
import jax
import jax.numpy as jnp
import numpy as np

import octax_core
import jax_training
import jax_update
import train_jax_ppo as ppo
from jax_networks import ActorCritic

NEG = -1e9  # the logit of an action the legal mask closes

PPO_METRICS = ("pg_loss", "v_loss", "entropy", "approx_kl", "clip_frac")
OPPONENTS = ("random", "scripted")
EVAL_STATS = ("win", "draw", "return_diff", "ended")
CSV_COLUMNS = (("update", "step", "wall_s", "env_steps_per_s", "train_return_seat0", "train_return_seat1",
                "train_episodes")
               + tuple(f"{stat}_vs_{opponent}" for opponent in OPPONENTS for stat in EVAL_STATS)
               + PPO_METRICS)
ELO_COLUMNS = ("player", "kind", "update", "elo", "games", "wins", "draws", "losses", "score")


@dataclasses.dataclass(frozen=True)
class Config(ppo.Config):
    """A self-play run: the PPO example's settings (smaller defaults, for a CPU), plus the pool,
    the evaluation and the Elo tournament. `total_steps` counts env steps (each one is two seats'
    samples); `eval_every` is in env steps too, as in the other examples."""

    game: str = "Duel"
    total_steps: int = 32 * 32 * 40  # 40 updates
    num_envs: int = 32
    num_steps: int = 32
    num_minibatches: int = 8
    eval_every: int = 32 * 32 * 10  # every 10 updates
    eval_envs: int = 32  # games per opponent, half from each seat
    eval_max_steps: Optional[int] = None
    eval_greedy: bool = False
    pool: int = 0  # K past selves as opponents; 0: pure self-play
    pool_prob: float = 0.5
    elo_games: int = 16  # games per pair of players, half from each seat
    elo_max_steps: int = 0  # 0: eval_max_steps' cap

    @property
    def batch_size(self) -> int:
        """Samples per update: both seats of every env and step."""
        return 2 * self.num_envs * self.num_steps

    @property
    def num_updates(self) -> int:
        return max(1, self.total_steps // (self.num_envs * self.num_steps))

    @property
    def env_steps_per_update(self) -> int:
        return self.num_envs * self.num_steps

    def check(self) -> None:
        super().check()
        if self.num_seeds != 1:
            raise ValueError(f"self-play trains one seed per run, got num_seeds = {self.num_seeds}")
        if self.pool < 0 or not 0.0 <= self.pool_prob <= 1.0:
            raise ValueError(f"pool must be >= 0 and pool_prob in [0, 1], got {self.pool}, {self.pool_prob}")
        if self.eval_envs < 2 or self.eval_envs % 2 or self.elo_games < 2 or self.elo_games % 2:
            raise ValueError(f"eval_envs and elo_games are even (half the games from each seat), got "
                             f"{self.eval_envs}, {self.elo_games}")


class Runner(NamedTuple):
    """The learner between updates (the fields `jax_update.make_learn` reads and replaces, plus
    the two-seat envs)."""

    params: Any
    opt_state: Any
    env_state: Any  # batched EnvState, (num_envs, ...)
    obs: jax.Array  # (num_envs, 2, F + 1, H, W) uint8
    episode_return: jax.Array  # (num_envs, 2) float32
    key: jax.Array
    updates: jax.Array


class SelfPlayStep(NamedTuple):
    """One step of the N envs, both seats: each field (num_envs, 2, ...)."""

    obs: jax.Array
    action: jax.Array
    log_prob: jax.Array
    value: jax.Array
    legal: jax.Array  # (num_envs, 2, num_actions) bool
    reward: jax.Array  # plus gamma * bootstrap where truncated
    done: jax.Array  # (num_envs, 2): the episode's end, the same for both seats
    weight: jax.Array  # 1: the learner's own sample; 0: a past self played it (pool)
    finished_return: jax.Array  # the seat's episode return where the episode ended this step, else 0


# --- acting -----------------------------------------------------------------------------------

def masked_logits(logits: jax.Array, legal: jax.Array) -> jax.Array:
    return jnp.where(legal, logits, NEG)


def v_legal(env: octax_core.MultiEnv) -> Callable:
    """Batched env states -> (num_envs, 2, num_actions) legal masks."""
    return jax.vmap(env.legal_action_mask)


def network_player(network: ActorCritic, greedy: bool = False) -> Callable:
    """A player from params: `(params, key, obs, state, seat, legal) -> actions`, all batched over
    envs (obs (n, F + 1, H, W) of its seat, seat (n,), legal (n, A))."""
    def play(params, key, obs, state, seat, legal):
        logits = masked_logits(network.apply(params, obs)[0], legal)
        return jnp.argmax(logits, -1) if greedy else jax.random.categorical(key, logits)
    return play


def random_player(params, key, obs, state, seat, legal):
    """Uniform over the legal actions."""
    return jax.random.categorical(key, jnp.where(legal, 0.0, NEG))


def scripted_player(env: octax_core.MultiEnv) -> Callable:
    policy = env.seats.scripted_policy

    def play(params, key, obs, state, seat, legal):
        both = jnp.stack([jax.vmap(lambda s: policy(s.machine, 0))(state),
                          jax.vmap(lambda s: policy(s.machine, 1))(state)], axis=1)
        return jnp.take_along_axis(both, seat[:, None], 1)[:, 0].astype(jnp.int32)
    return play


# --- training ---------------------------------------------------------------------------------

def make_train(config: Config, env: octax_core.MultiEnv, env_params, network=None) -> tuple[Callable, Callable, Any]:
    """`init(key) -> Runner` and `update(runner, pool, pool_count) -> (runner, metrics)` (pure;
    jit them), and the network. `pool` is the stacked snapshots ((max(K, 1), ...) leaves),
    `pool_count` how many are filled; with `config.pool == 0` neither is read. `network`: a flax
    module `obs -> (logits, values)`; None: the PPO example's `ActorCritic`."""
    config.check()
    if not env.config.autoreset:
        raise ValueError("self-play training needs a MultiEnv made with autoreset=True")
    network = ActorCritic(env.num_actions) if network is None else network
    optimizer = jax_update.make_optimizer(config)
    n, legal_of = config.num_envs, v_legal(env)
    v_reset = jax.vmap(env.reset, in_axes=(0, None))
    v_step = jax.vmap(env.step, in_axes=(0, 0, 0, None))

    def both_seats(params, obs):
        """(n, 2, ...) observations -> logits (n, 2, A) and values (n, 2)."""
        logits, value = network.apply(params, obs.reshape((2 * n,) + obs.shape[2:]))
        return logits.reshape(n, 2, -1), value.reshape(n, 2)

    def init(key):
        key, net_key, env_key = jax.random.split(key, 3)
        obs, env_state = v_reset(jax.random.split(env_key, n), env_params)
        params = network.init(net_key, obs[:1, 0])
        return Runner(params, optimizer.init(params), env_state, obs, jnp.zeros((n, 2), jnp.float32), key,
                      jnp.int32(0))

    def rollout(runner: Runner, pool, pool_count):
        key, pick_key, past_key, seat_key = jax.random.split(runner.key, 4)
        runner = runner._replace(key=key)
        if config.pool:
            past_params = jax.tree.map(lambda x: x[jax.random.randint(pick_key, (), 0, pool_count)], pool)
            past_env = jax.random.bernoulli(past_key, config.pool_prob, (n,))
            past_seat = jax.random.randint(seat_key, (n,), 0, 2)
            played_by_past = past_env[:, None] & (jnp.arange(2)[None] == past_seat[:, None])  # (n, 2)
        else:
            played_by_past = jnp.zeros((n, 2), jnp.bool_)

        def env_step(runner: Runner, _):
            key, act_key, past_act_key, step_key = jax.random.split(runner.key, 4)
            legal = legal_of(runner.env_state)
            logits, value = both_seats(runner.params, runner.obs)
            logits = masked_logits(logits, legal)
            action = jax.random.categorical(act_key, logits)
            if config.pool:
                past_action = jax.random.categorical(
                    past_act_key, masked_logits(both_seats(past_params, runner.obs)[0], legal))
                action = jnp.where(played_by_past, past_action, action)
            log_prob = jnp.take_along_axis(jax.nn.log_softmax(logits), action[..., None], -1)[..., 0]
            obs, env_state, reward, terminated, truncated, info = v_step(
                jax.random.split(step_key, n), runner.env_state, action, env_params)
            # A time limit is not a terminal state: a truncated episode is credited gamma * value
            # of its last observation (rare, so the network runs only then).
            final_value = jax.lax.cond(truncated.any(), lambda: both_seats(runner.params, info["final_observation"])[1],
                                       lambda: jnp.zeros((n, 2), jnp.float32))
            done = jnp.broadcast_to((terminated | truncated)[:, None], (n, 2))
            episode_return = runner.episode_return + reward
            step = SelfPlayStep(runner.obs, action, log_prob, value, legal,
                                reward + config.gamma * jnp.where(truncated[:, None], final_value, 0.0), done,
                                (~played_by_past).astype(jnp.float32), jnp.where(done, episode_return, 0.0))
            runner = runner._replace(env_state=env_state, obs=obs, key=key,
                                     episode_return=jnp.where(done, 0.0, episode_return))
            return runner, step

        return jax.lax.scan(env_step, runner, None, config.num_steps)

    learn = jax_update.make_learn(config, optimizer, lambda params, minibatch: _loss(params, network, config, minibatch))

    def update(runner: Runner, pool=None, pool_count=None):
        runner, traj = rollout(runner, pool, pool_count)
        seats = lambda x: x.reshape((config.num_steps, 2 * n) + x.shape[3:])  # noqa: E731  (T, n, 2, ...) -> (T, 2n, ...)
        traj2 = jax.tree.map(seats, traj)
        last_value = both_seats(runner.params, runner.obs)[1].reshape(2 * n)
        advantages, targets = ppo._gae(traj2.reward, traj2.done, traj2.value, last_value, config.gamma,
                                       config.gae_lambda)
        runner, metrics = learn(runner, (traj2.obs, traj2.action, traj2.legal, traj2.log_prob, traj2.value,
                                         advantages, targets, traj2.weight))
        ended = traj.done[..., 0]
        return runner, {**metrics, "finished_return_sum": traj.finished_return.sum((0, 1)),
                        "finished_episodes": ended.sum()}

    return init, update, network


def _loss(params, network: ActorCritic, config: Config, minibatch):
    """The PPO example's clipped loss (`train_jax_ppo._ppo_loss`) over legal-masked logits, each
    sample weighted (0 for a past self's samples)."""
    obs, action, legal, old_log_prob, old_value, advantage, target, weight = minibatch
    logits, value = network.apply(params, obs)
    log_probs = jax.nn.log_softmax(masked_logits(logits, legal))
    log_prob = jnp.take_along_axis(log_probs, action[:, None], 1)[:, 0]
    total = jnp.maximum(weight.sum(), 1.0)
    mean = lambda x: (x * weight).sum() / total  # noqa: E731
    entropy = mean(-(jnp.where(legal, jnp.exp(log_probs) * log_probs, 0.0)).sum(-1))
    log_ratio = log_prob - old_log_prob
    ratio = jnp.exp(log_ratio)
    adv_mean = mean(advantage)
    advantage = (advantage - adv_mean) / (jnp.sqrt(mean(jnp.square(advantage - adv_mean))) + 1e-8)
    clipped = jnp.clip(ratio, 1 - config.clip_eps, 1 + config.clip_eps)
    pg_loss = -mean(jnp.minimum(ratio * advantage, clipped * advantage))
    v_loss = jnp.square(value - target)
    if config.clip_value_loss:
        v_clipped = old_value + jnp.clip(value - old_value, -config.clip_eps, config.clip_eps)
        v_loss = jnp.maximum(v_loss, jnp.square(v_clipped - target))
    v_loss = 0.5 * mean(v_loss)
    loss = pg_loss + config.vf_coef * v_loss - config.ent_coef * entropy
    return loss, {"pg_loss": pg_loss, "v_loss": v_loss, "entropy": entropy,
                  "approx_kl": mean((ratio - 1) - log_ratio),
                  "clip_frac": mean((jnp.abs(ratio - 1) > config.clip_eps).astype(jnp.float32))}


# --- matches: evaluation and the Elo round robin -----------------------------------------------

def make_match(env: octax_core.MultiEnv, env_params, num_games: int, max_steps: int,
               players: Sequence[Callable]) -> Callable:
    """`match(kind_a, params_a, kind_b, params_b, key) -> (return_a, return_b, ended)`, each
    (num_games,), jitted once for every pairing: `kind_a`, `kind_b` index `players` (each
    `(params, key, obs, state, seat, legal) -> actions`, batched over games; `lax.switch` runs the
    one chosen). A plays seat 0 in the first half of the games and seat 1 in the second, B the
    other seat; each game to its end or `max_steps`."""
    if env.config.autoreset:
        raise ValueError("make_match needs a MultiEnv made with autoreset=False (one game per env)")
    v_reset = jax.vmap(env.reset, in_axes=(0, None))
    v_step = jax.vmap(env.step, in_axes=(0, 0, 0, None))
    legal_of = v_legal(env)
    a_seat = (jnp.arange(num_games) >= num_games // 2).astype(jnp.int32)
    b_seat = 1 - a_seat
    rows = jnp.arange(num_games)
    players = [lambda *args, p=p: p(*args).astype(jnp.int32) for p in players]

    def match(kind_a, params_a, kind_b, params_b, key):
        key, reset_key = jax.random.split(key)
        obs, state = v_reset(jax.random.split(reset_key, num_games), env_params)
        zeros = jnp.zeros((num_games, 2), jnp.float32)

        def running(carry):
            t, _, _, _, _, ended = carry
            return (t < max_steps) & ~ended.all()

        def body(carry):
            t, key, obs, state, returns, ended = carry
            key, a_key, b_key, step_key = jax.random.split(key, 4)
            legal = legal_of(state)
            act_a = jax.lax.switch(kind_a, players, params_a, a_key, obs[rows, a_seat], state, a_seat,
                                   legal[rows, a_seat])
            act_b = jax.lax.switch(kind_b, players, params_b, b_key, obs[rows, b_seat], state, b_seat,
                                   legal[rows, b_seat])
            actions = jnp.where(a_seat[:, None] == jnp.arange(2)[None], act_a[:, None], act_b[:, None])
            obs, state, reward, terminated, truncated, _ = v_step(
                jax.random.split(step_key, num_games), state, actions, env_params)
            # Ended games stand still and pay 0 (no autoreset), so summing is safe.
            return t + 1, key, obs, state, returns + reward, ended | terminated | truncated

        carry = (jnp.int32(0), key, obs, state, zeros, jnp.zeros(num_games, jnp.bool_))
        _, _, _, _, returns, ended = jax.lax.while_loop(running, body, carry)
        return returns[rows, a_seat], returns[rows, b_seat], ended

    return jax.jit(match, compiler_options=env.compiler_options)  # the platform's (exact; faster)


def match_stats(return_a, return_b, ended) -> dict[str, float]:
    """A's win and draw rates, mean return difference (A - B) and the fraction of games ended."""
    return_a, return_b = np.asarray(return_a), np.asarray(return_b)
    return {"win": float((return_a > return_b).mean()), "draw": float((return_a == return_b).mean()),
            "return_diff": float((return_a - return_b).mean()), "ended": float(np.asarray(ended).mean())}


def bradley_terry_elo(wins: np.ndarray, games: np.ndarray, anchor: int, iterations: int = 2000) -> np.ndarray:
    """Elo ratings from a round robin: `wins[i, j]` is i's points against j (a win 1, a draw 0.5),
    `games[i, j]` their games. A Bradley-Terry model (P(i beats j) = p_i / (p_i + p_j)) fitted by
    maximum likelihood with Hunter's MM updates, one virtual draw added to every pair that played;
    returned as 400 log10(p) with player `anchor` at 0."""
    wins = np.asarray(wins, np.float64).copy()
    games = np.asarray(games, np.float64).copy()
    played = games > 0
    wins += 0.5 * played
    games += played
    strength = np.ones(len(wins))
    for _ in range(iterations):
        denom = (games / (strength[:, None] + strength[None, :])).sum(1)
        new = wins.sum(1) / np.maximum(denom, 1e-12)
        new /= np.exp(np.log(new).mean())
        if np.allclose(new, strength, rtol=1e-10, atol=0):
            strength = new
            break
        strength = new
    elo = 400 * np.log10(strength)
    return elo - elo[anchor]


class Matches:
    """The players of one run, by kind: the network (`checkpoint`, any params), `random` and
    `scripted` (where the game has one); `matches(games, max_steps)` is the one compiled match
    for that many games and that cap (evaluation and Elo share it where both agree), and
    `play(match, kind_a, params_a, kind_b, params_b, key)` plays it."""

    def __init__(self, env, env_params, network, greedy: bool):
        self.env, self.env_params, self.cache = env, env_params, {}
        players = {"checkpoint": network_player(network, greedy), "random": random_player}
        if env.seats.scripted_policy is not None:
            players["scripted"] = scripted_player(env)
        self.kinds = tuple(players)
        self._players = tuple(players.values())
        self.dummy = None  # params the random and scripted players are passed (the match's shapes)

    def __call__(self, games: int, max_steps: int) -> Callable:
        if (games, max_steps) not in self.cache:
            self.cache[games, max_steps] = make_match(self.env, self.env_params, games, max_steps, self._players)
        return self.cache[games, max_steps]

    def play(self, match: Callable, kind_a: str, params_a, kind_b: str, params_b, key):
        params_a = self.dummy if params_a is None else params_a
        params_b = self.dummy if params_b is None else params_b
        return jax.device_get(match(jnp.int32(self.kinds.index(kind_a)), params_a,
                                    jnp.int32(self.kinds.index(kind_b)), params_b, key))


def elo_round_robin(matches: Matches, config: Config, checkpoints: list[tuple[int, Any]], key,
                    max_steps: int) -> list[dict]:
    """Every pair of players (each checkpoint, random, scripted where the game has one) plays
    `config.elo_games` games; returns one row per player (ELO_COLUMNS), best first."""
    players = [(f"update {u}", "checkpoint", u, p) for u, p in checkpoints]
    players += [(kind, kind, "", None) for kind in OPPONENTS if kind in matches.kinds]
    match = matches(config.elo_games, max_steps)
    count = len(players)
    wins, games = np.zeros((count, count)), np.zeros((count, count))
    record = np.zeros((count, 3))  # wins, draws, losses
    for i in range(count):
        for j in range(i + 1, count):
            ra, rb, _ = matches.play(match, players[i][1], players[i][3], players[j][1], players[j][3],
                                     jax.random.fold_in(key, i * count + j))
            w, d = float((ra > rb).sum()), float((ra == rb).sum())
            lost = len(ra) - w - d
            wins[i, j], wins[j, i] = w + 0.5 * d, lost + 0.5 * d
            games[i, j] = games[j, i] = len(ra)
            record[i] += (w, d, lost)
            record[j] += (lost, d, w)
    random_index = next(k for k, p in enumerate(players) if p[1] == "random")
    elo = bradley_terry_elo(wins, games, random_index)
    rows = [{"player": p[0], "kind": p[1], "update": p[2], "elo": round(float(elo[k]), 1) + 0.0,
             "games": int(games[k].sum()), "wins": int(record[k, 0]), "draws": int(record[k, 1]),
             "losses": int(record[k, 2]), "score": round(float(wins[k].sum() / games[k].sum()), 3)}
            for k, p in enumerate(players)]
    return sorted(rows, key=lambda r: -r["elo"])


# --- the run ----------------------------------------------------------------------------------

def train(config: Config, out_dir, game=None, rom=None, network=None) -> dict:
    """Trains, evaluates, saves checkpoints, plays the Elo round robin; writes progress.csv,
    learning_curve.png, checkpoints/, params.msgpack, elo.csv and config.json to `out_dir`.
    `game` (an id or a `GameSpec` with seats) and `rom` default to `config.game` and the ROM store;
    `network` (a flax module `obs -> (logits, values)`) to the PPO example's `ActorCritic`.
    Returns a summary: paths, the CSV rows, the Elo rows, the final params."""
    config.check()
    out_dir = Path(out_dir)
    (out_dir / "checkpoints").mkdir(parents=True, exist_ok=True)
    game = config.game if game is None else game
    overrides = dict(config.env_overrides)
    env, env_params = octax_core.make_multi(game, rom=rom, autoreset=True, **overrides)
    eval_env, _ = octax_core.make_multi(game, rom=rom, autoreset=False, **overrides)
    eval_steps = config.eval_max_steps or int(env_params.max_episode_steps)
    elo_steps = config.elo_max_steps or eval_steps
    init, update, network = make_train(config, env, env_params, network)
    has_scripted = env.seats.scripted_policy is not None
    matches = Matches(eval_env, env_params, network, config.eval_greedy)
    eval_match = matches(config.eval_envs, eval_steps)
    (out_dir / "config.json").write_text(json.dumps(
        {"algorithm": "self-play PPO", "env_id": env.spec.id, "command": sys.argv, **dataclasses.asdict(config)},
        indent=2, default=str) + "\n")

    train_key, eval_key, elo_key = jax.random.split(jax.random.key(config.seed), 3)
    runner = jax.jit(init)(train_key)
    matches.dummy = jax.tree.map(jnp.copy, runner.params)
    pool_size = max(config.pool, 1)
    pool = jax.tree.map(lambda x: jnp.stack([x] * pool_size), runner.params)
    pool_count = 1
    start = time.perf_counter()
    update = jax.jit(update, donate_argnums=0, compiler_options=env.compiler_options).lower(
        runner, pool, jnp.int32(pool_count)).compile()
    print(f"compiled the self-play update in {time.perf_counter() - start:.1f} s ({config.num_envs} envs x 2 seats x "
          f"{config.num_steps} steps, {config.num_updates} updates, pool {config.pool})")

    eval_interval = config.num_updates
    if config.eval_every:
        eval_interval = max(1, round(config.eval_every / config.env_steps_per_update))
    log = SelfPlayLog(out_dir, f"self-play PPO on {env.spec.id} ({config.num_envs} envs x 2 seats"
                      + (f", pool {config.pool})" if config.pool else ")"), has_scripted)
    checkpoints, totals, train_s, start = [], {}, 0.0, time.perf_counter()
    for i in range(config.num_updates + 1):
        if i % eval_interval == 0 or i == config.num_updates:
            stats = {}
            for kind in OPPONENTS[:1 + has_scripted]:
                stats[kind] = match_stats(*matches.play(eval_match, "checkpoint", runner.params, kind, None,
                                                        jax.random.fold_in(eval_key, i)))
            params = jax.tree.map(np.array, jax.device_get(runner.params))  # copies: the update donates its buffers
            checkpoints.append((i, params))
            (out_dir / "checkpoints" / f"params-u{i:05d}.msgpack").write_bytes(flax.serialization.to_bytes(params))
            if config.pool:  # the snapshot joins the pool (a ring of the last K)
                slot = (len(checkpoints) - 1) % config.pool
                pool = jax.tree.map(lambda stack, x: stack.at[slot].set(x), pool, runner.params)
                pool_count = min(len(checkpoints), config.pool)
            row = log.add(i, i * config.env_steps_per_update, time.perf_counter() - start, train_s, stats, totals)
            print(f"update {i:4d}  steps {row['step']:8d}  train return {row['train_return_seat0']:.2f} / "
                  f"{row['train_return_seat1']:.2f}  vs random: win {row['win_vs_random']:.2f} diff "
                  f"{row['return_diff_vs_random']:+.2f}" + (
                      f"  vs scripted: win {row['win_vs_scripted']:.2f} diff {row['return_diff_vs_scripted']:+.2f}"
                      if has_scripted else ""), flush=True)
            totals = {}
        if i == config.num_updates:
            break
        t0 = time.perf_counter()
        runner, metrics = update(runner, pool, jnp.int32(pool_count))
        metrics = jax.device_get(metrics)
        train_s += time.perf_counter() - t0
        for k, v in metrics.items():
            totals[k] = totals.get(k, 0.0) + np.asarray(v, np.float64)
        totals["updates"] = totals.get("updates", 0) + 1

    params_path = out_dir / "params.msgpack"
    params_path.write_bytes(flax.serialization.to_bytes(jax.device_get(runner.params)))
    steps_per_s = config.num_updates * config.env_steps_per_update / train_s
    print(f"training speed: {steps_per_s:,.0f} env steps/s ({2 * steps_per_s:,.0f} seat samples/s), "
          f"{train_s:.1f} s of updates; wall {time.perf_counter() - start:.0f} s")

    t0 = time.perf_counter()
    elo_rows = elo_round_robin(matches, config, checkpoints, elo_key, elo_steps)
    elo_path = out_dir / "elo.csv"
    with open(elo_path, "w", newline="") as f:
        writer = csv.DictWriter(f, ELO_COLUMNS)
        writer.writeheader()
        writer.writerows(elo_rows)
    print(f"Elo (Bradley-Terry, random = 0; {config.elo_games} games a pair, {time.perf_counter() - t0:.0f} s):")
    print(format_table(elo_rows, ELO_COLUMNS))
    return {"csv": log.csv_path, "png": log.png_path, "elo": elo_path, "params": params_path,
            "checkpoints": sorted((out_dir / "checkpoints").glob("*.msgpack")), "rows": log.rows,
            "elo_rows": elo_rows, "final_params": runner.params, "env_steps_per_s": steps_per_s}


def format_table(rows: list[dict], columns: Sequence[str]) -> str:
    widths = [max(len(c), *(len(str(r[c])) for r in rows)) for c in columns]
    lines = ["  ".join(c.ljust(w) for c, w in zip(columns, widths))]
    lines += ["  ".join(str(r[c]).ljust(w) for c, w in zip(columns, widths)) for r in rows]
    return "\n".join(lines)


class SelfPlayLog:
    """One CSV row per evaluation, and the curves redrawn each time."""

    def __init__(self, out_dir: Path, title: str, has_scripted: bool):
        self.csv_path, self.png_path = out_dir / "progress.csv", out_dir / "learning_curve.png"
        self.title, self.has_scripted, self.rows = title, has_scripted, []
        with open(self.csv_path, "w", newline="") as f:
            csv.writer(f).writerow(CSV_COLUMNS)

    def add(self, update: int, step: int, wall_s: float, train_s: float, stats: dict, totals: dict) -> dict:
        n = totals.get("updates", 0)
        episodes = float(totals.get("finished_episodes", 0.0))
        returns = np.asarray(totals.get("finished_return_sum", np.zeros(2))) / episodes if episodes else [math.nan] * 2
        row = {"update": update, "step": step, "wall_s": round(wall_s, 2),
               "env_steps_per_s": round(step / train_s, 1) if train_s else math.nan,
               "train_return_seat0": float(returns[0]), "train_return_seat1": float(returns[1]),
               "train_episodes": int(episodes)}
        for opponent in OPPONENTS:
            for stat in EVAL_STATS:
                row[f"{stat}_vs_{opponent}"] = stats[opponent][stat] if opponent in stats else math.nan
        for name in PPO_METRICS:
            row[name] = float(totals[name]) / n if n else math.nan
        self.rows.append(row)
        with open(self.csv_path, "a", newline="") as f:
            csv.DictWriter(f, CSV_COLUMNS).writerow(row)
        self._plot()
        return row

    def _plot(self) -> None:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        step = np.array([r["step"] for r in self.rows])
        fig, (win_ax, ret_ax) = plt.subplots(1, 2, figsize=(11, 4))
        for opponent in OPPONENTS[:1 + self.has_scripted]:
            win_ax.plot(step, [r[f"win_vs_{opponent}"] for r in self.rows], "o-", label=f"win rate vs {opponent}")
            win_ax.plot(step, [r[f"draw_vs_{opponent}"] for r in self.rows], ":", alpha=0.6,
                        label=f"draw rate vs {opponent}")
        win_ax.set_ylim(-0.03, 1.03)
        win_ax.set_xlabel("env steps")
        win_ax.set_ylabel("fraction of evaluation games")
        win_ax.set_title(self.title, fontsize="medium")
        win_ax.legend(loc="best", fontsize="small")
        for seat in (0, 1):
            ret_ax.plot(step, [r[f"train_return_seat{seat}"] for r in self.rows], ".--", label=f"seat {seat}")
        for opponent in OPPONENTS[:1 + self.has_scripted]:
            ret_ax.plot(step, [r[f"return_diff_vs_{opponent}"] for r in self.rows], "o-",
                        label=f"eval return - {opponent}'s")
        ret_ax.set_xlabel("env steps")
        ret_ax.set_ylabel("episode return")
        ret_ax.set_title("training episodes (self-play) and evaluation margin", fontsize="medium")
        ret_ax.legend(loc="best", fontsize="small")
        fig.tight_layout()
        fig.savefig(self.png_path, dpi=100)
        plt.close(fig)


# --- command line -----------------------------------------------------------------------------

HELP = {
    **ppo.HELP,
    "game": "a two-player octax game id (octax_core.list_games(players=2))",
    "total_steps": "env steps over all envs (each step is a sample for each of the two seats)",
    "num_steps": "rollout length per env and update",
    "num_minibatches": "Adam steps per epoch (2 * num_envs * num_steps must divide)",
    "num_seeds": "must be 1: self-play trains one seed per run",
    "eval_every": "env steps between evaluations and checkpoints; 0: only at the start and the end",
    "eval_envs": "evaluation games per opponent (random, scripted), half from each seat",
    "eval_max_steps": "step cap per evaluation game; None: the env's max_episode_steps",
    "eval_greedy": "evaluate the argmax action (default: sampled from the policy)",
    "pool": "K: play one of the last K snapshots (one per evaluation) as the opponent with probability "
            "pool_prob; 0: pure self-play",
    "pool_prob": "per env and update, the chance that one seat is played by a past self",
    "elo_games": "games per pair of players in the final Elo round robin, half from each seat",
    "elo_max_steps": "step cap per Elo game; 0: eval_max_steps' cap",
}


def main(argv: Optional[Sequence[str]] = None) -> dict:
    """The command line: flags (one per `Config` field, as the other examples), training, summary."""
    config, out_dir = jax_training.parse_args(Config, HELP, __doc__.split("\n\n")[0], "runs/jax_selfplay", argv)
    print(f"self-play PPO on {config.game}: {config}")
    summary = train(config, out_dir)
    print(f"wrote {summary['csv']}, {summary['png']} and {summary['elo']}")
    return summary


if __name__ == "__main__":
    main(sys.argv[1:])
