"""Multi-task PPO: one agent, pure JAX, on several octax games in one batch (`octax_core.make_mix`).

    python examples/train_jax_multitask.py --games Airplane Brix Deep8 Filter Pong Squash VerticalBrix WipeOff \\
        --num-envs 64 --total-steps 524288 --out-dir runs/jax_multitask/octax8
    python examples/train_jax_multitask.py ... --single-baseline   # then one PPO agent per game, same steps per game

The learner is the PPO example's (examples/train_jax_ppo.py: its GAE, clipped loss, settings and
sampled-policy evaluation), built from the shared pieces (examples/jax_update.py: the rollout and
the minibatch epochs, unchanged; examples/jax_training.py: the command line). What is multi-task's:

- The env is `octax_core.make_mix(games)`, one compiled program in which each of the `--num-envs`
  envs plays one game. The action space is the largest game's (`env.num_actions`); an action past
  an env's game's last is a no-op, so the policy's logits are masked with the game's action mask
  (`MixEnv.action_mask`; the `Masked` module sets an illegal action's logit to -1e9 after the
  network, so acting, the loss's log-probs and entropy and the evaluation all see the masked
  policy, and an illegal action is never sampled: each update counts them, `illegal_actions`).
- Lanes are fixed per game: env i plays game i mod G for the whole run (its first reset and every
  autoreset are forced to that game), so every game gets exactly num_envs / G envs and
  total_steps / G env steps: the same data per game as a single-game agent given total_steps / G
  steps. (The mix's own autoreset, `--redraw-games`, draws each new episode's game from uniform
  weights; a lane then stays on a game for one episode, so the share of env steps a game gets is
  proportional to its mean episode length: in the default eight, Airplane's ~1,000-step episodes
  against Brix's ~40 at the start. Each update logs the env steps each game got.)
- The agent sees each env's observation as a pair (frames, game index). With `--game-input` (the
  default) the network is told the game: its one-hot is appended to the CNN torso's 1,024 features
  before the actor and critic heads (the paper's network otherwise, examples/jax_networks.py);
  `--no-game-input` leaves it out, so the policy must tell the games apart from the screen. The
  game index always selects the action mask (the mask is the env's, not something learned).
- One reward scale for all games (no per-game normalisation, no PopArt): advantages are
  normalised per minibatch as in the PPO example; the value head sees the games' raw returns.
- Evaluation every `--eval-every` env steps (all games together): `--eval-envs` episodes *per game*
  (G x eval_envs envs in one batch, game forced per env), actions sampled from the masked policy,
  each episode to its end or `--eval-max-steps`. A uniform-random policy over each game's legal
  actions is measured the same way at the start. Logged per game: mean and std of the returns,
  the normalized score (`octax_gym.scores.normalized_score`: (return - random) / (reference -
  random) with the committed random and reference scores of docs/scores.md) and, over the games,
  the interquartile mean (`octax_gym.scores.iqm`, of the G per-game normalized means) and the mean.
- `--single-baseline`: after the multi-task run, one PPO agent per game with
  examples/train_jax_ppo.py's `train`, each for total_steps / G steps (the multi-task agent's
  steps per game) with the same settings (`--baseline-num-envs` to give them another number of
  envs; the default is the same num_envs, so a single agent makes G times fewer updates of the same
  size), evaluated the same way, normalized the same way; writes `comparison.csv` (one row per game,
  plus the IQM and the mean) and `comparison.png`, and prints the table. A finished single-game run
  already in `out_dir/single-<game>/` with the same settings is read, not trained again, so the
  baselines can be trained apart (train_jax_ppo.py with the flags that config.json shows) and
  `--compare-only` (no multi-task training: reads `final.csv`) writes the comparison.

Writes `progress.csv` (one row per evaluation: per-game returns, normalized scores, IQM, per-game
training returns and env-step shares, the PPO losses), `learning_curve.png` (per-game normalized
scores and their IQM), `final.csv` (per game: random, reference, return, normalized score),
`params.msgpack` and `config.json` to `--out-dir`. One seed per run. See docs/results.md, "Multi-task".
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import sys
import time
from pathlib import Path
from typing import Callable, Optional, Sequence

import flax.linen as nn
import flax.serialization
import jax
import jax.numpy as jnp
import numpy as np

import octax_core
import jax_training
import jax_update
import train_jax_ppo as ppo
from jax_networks import ActorCritic
from octax_gym import scores

NEG = -1e9  # the logit of an action the game's mask closes
DEFAULT_GAMES = ("Airplane", "Brix", "Deep8", "Filter", "Pong", "Squash", "VerticalBrix", "WipeOff")
PPO_METRICS = ("pg_loss", "v_loss", "entropy", "approx_kl", "clip_frac")
COMPARISON_COLUMNS = ("game", "steps_per_game", "random_ref", "reference", "multi_return", "single_return",
                      "multi_normalized", "single_normalized")
FINAL_COLUMNS = ("game", "random_measured", "random_ref", "reference", "eval_return", "eval_std", "eval_ended_frac",
                 "normalized")


@dataclasses.dataclass(frozen=True)
class Config(ppo.Config):
    """A multi-task run: the PPO example's settings (smaller defaults, for a CPU), the games, how
    the network sees them, and the single-game baseline."""

    game: str = "multitask"  # names the default --out-dir only; the games are `games`
    games: str = ",".join(DEFAULT_GAMES)  # comma-separated (the command line also takes them space-separated)
    total_steps: int = 8 * 65_536  # over all games: total_steps / G per game
    num_envs: int = 64
    num_steps: int = 32
    num_minibatches: int = 8
    eval_every: int = 131_072
    eval_envs: int = 16  # per game
    game_input: bool = True
    redraw_games: bool = False
    single_baseline: bool = False
    baseline_num_envs: int = 0  # 0: num_envs
    compare_only: bool = False

    @property
    def game_list(self) -> tuple[str, ...]:
        return tuple(g.strip() for g in self.games.split(",") if g.strip())

    @property
    def steps_per_game(self) -> int:
        """Env steps each game gets (with fixed lanes, exactly): the single-game agents' total_steps."""
        return self.num_updates * self.batch_size // len(self.game_list)

    def check(self) -> None:
        super().check()
        games = self.game_list
        if len(games) < 2 or len(set(games)) != len(games):
            raise ValueError(f"games must name at least two different games, got {list(games)}")
        if self.num_seeds != 1:
            raise ValueError(f"the multi-task example trains one seed per run, got num_seeds = {self.num_seeds}")
        if self.num_envs % len(games):
            raise ValueError(f"num_envs = {self.num_envs} must be a multiple of the number of games ({len(games)}): "
                             "each game gets the same number of envs")


# --- the env as the agent sees it ----------------------------------------------------------------

class TaskEnv:
    """A `MixEnv` (made with autoreset=False) whose observations are (frames, game index) pairs and
    which resets itself: an ended episode restarts on the same game (fixed lanes) or, with
    `redraw`, on a game drawn from the mix's weights (what the mix's own autoreset does, with the
    same keys). What `jax_update.make_rollout` needs: `config.autoreset`, `step`, and
    `info["final_observation"]` (the ended episode's (frames, game))."""

    def __init__(self, mix: octax_core.Env, redraw: bool = False):
        if mix.config.autoreset:
            raise ValueError("TaskEnv resets the mix itself: make it with autoreset=False")
        self.mix, self.redraw = mix, redraw
        self.config = dataclasses.replace(mix.config, autoreset=True)
        self.num_actions, self.games = mix.num_actions, mix.games

    def reset(self, key: jax.Array, params, game=None):
        obs, state = self.mix.reset(key, params, game)
        return (obs, state.game), state

    def step(self, key: jax.Array, state, action, params):
        step_key, reset_key = jax.random.split(key)  # as Env.step splits it
        obs, state, reward, terminated, truncated, info = self.mix.step_env(step_key, state, action, params)
        info = {**info, "final_observation": (obs, state.game), "_final": state.done}
        fresh = self.mix.reset_env(reset_key, params, None if self.redraw else state.game)
        obs, state = jax.tree.map(lambda new, old: jnp.where(state.done, new, old), fresh, (obs, state))
        return (obs, state.game), state, reward, terminated, truncated, info


def lane_games(num_envs: int, num_games: int) -> jax.Array:
    """The game of each env of a batch: env i plays game i mod G."""
    return jnp.arange(num_envs, dtype=jnp.int32) % num_games


# --- the network --------------------------------------------------------------------------------

def MultiTaskActorCritic(num_actions: int, num_games: int, game_input: bool = True) -> nn.Module:
    """The PPO example's network (`jax_networks.ActorCritic`) on (frames, game) pairs: with
    `game_input`, the game's one-hot joins the torso's features before the heads; without, the
    game is not read."""
    return ActorCritic(num_actions, num_games if game_input else 0)


class Masked(nn.Module):
    """`net` ((frames, game) -> (logits, values)) with each env's logits masked by its game's
    legal actions: an action the game does not take gets logit -1e9, so its probability is 0
    (exactly, in float32) when acting, in the loss's log-probs and entropy, and in evaluation."""

    net: nn.Module
    legal: tuple  # (num_games, num_actions) bools, nested tuples (a constant of the program; hashable)

    def __call__(self, obs) -> tuple[jax.Array, jax.Array]:
        logits, value = self.net(obs)
        return masked_logits(logits, obs[1], self.legal), value


def masked_logits(logits: jax.Array, game: jax.Array, legal) -> jax.Array:
    """(B, A) logits with the actions game (B,) does not take set to -1e9 (`legal`: (G, A) bools)."""
    return jnp.where(jnp.asarray(np.array(legal, bool))[game], logits, NEG)


def legal_table(mix) -> tuple:
    """The mix's action masks, (num_games, num_actions) bools as nested tuples: row g marks the
    actions game g takes, no-op (0) and its keys (1 .. its number of keys), as `MixEnv.action_mask`."""
    return tuple(tuple(a <= len(spec.action_keys) for a in range(mix.num_actions)) for spec in mix.specs)


def random_policy(legal: np.ndarray) -> Callable:
    """Uniform over each env's game's legal actions: `(params, key, (frames, game)) -> actions`."""
    return lambda _, key, obs: jax.random.categorical(key, masked_logits(jnp.zeros((obs[1].shape[0], len(legal[0]))),
                                                                         obs[1], legal))


# --- training -----------------------------------------------------------------------------------

def make_envs(config: Config, games=None, roms=None):
    """The mix (autoreset=False: evaluation plays it directly), the training `TaskEnv` and the params."""
    games = config.game_list if games is None else games
    mix, params = octax_core.make_mix(list(games), roms=roms, autoreset=False, **dict(config.env_overrides))
    return mix, TaskEnv(mix, config.redraw_games), params


def make_train(config: Config, env: TaskEnv, env_params, network: Optional[nn.Module] = None
               ) -> jax_training.Trainer:
    """PPO on `env`: `ppo.make_train`'s update with the multi-task network, fixed-lane resets and
    per-game training stats; a `jax_training.Trainer` (jit `update` yourself). `network`: a flax
    module (frames, game) -> (logits (B, A), values (B,)), masked here; None: `MultiTaskActorCritic`."""
    config.check()
    num_games, n = len(env.games), config.num_envs
    if network is None:
        network = MultiTaskActorCritic(env.num_actions, num_games, config.game_input)
    network = Masked(network, legal_table(env.mix))
    optimizer = jax_update.make_optimizer(config)

    def init(key):
        key, net_key, env_key = jax.random.split(key, 3)
        obs, env_state = jax.vmap(env.reset, in_axes=(0, None, 0))(
            jax.random.split(env_key, n), env_params, lane_games(n, num_games))
        params = network.init(net_key, jax.tree.map(lambda x: x[:1], obs))
        return jax_update.RunnerState(params, optimizer.init(params), env_state, obs, jnp.zeros(n, jnp.float32),
                                      key, jnp.int32(0))

    def act(params, key, obs, _):
        logits, value = network.apply(params, obs)
        action = jax.random.categorical(key, logits)
        log_prob = jnp.take_along_axis(jax.nn.log_softmax(logits), action[:, None], 1)[:, 0]
        return action, ppo.OldPolicy(log_prob, value)

    def critic(params, obs):
        return network.apply(params, obs)[1]

    rollout = jax_update.make_rollout(config, env, env_params, act, critic)
    learn = jax_update.make_learn(config, optimizer,
                                  lambda params, minibatch: ppo._ppo_loss(params, network, config, minibatch))

    def update(runner: jax_update.RunnerState):
        runner, traj = rollout(runner)
        old = traj.policy_out
        advantages, targets = ppo._gae(traj.reward, traj.done, old.value, critic(runner.params, runner.obs),
                                       config.gamma, config.gae_lambda)
        runner, metrics = learn(runner, (traj.obs, traj.action, old.log_prob, old.value, advantages, targets))
        by_game = jax.nn.one_hot(traj.obs[1], num_games)  # (T, n, G): the game each sample's env played
        return runner, {**metrics, **jax_update.episode_totals(traj),
                        "steps_by_game": by_game.sum((0, 1)),
                        "episodes_by_game": (by_game * traj.done[..., None]).sum((0, 1)),
                        "return_sum_by_game": (by_game * traj.finished_return[..., None]).sum((0, 1)),
                        "illegal_actions": (~jnp.asarray(np.array(network.legal))[traj.obs[1], traj.action]).sum()}

    return jax_training.Trainer("PPO", network, init, update, ppo.policy_act(network), lambda r: r.params,
                                PPO_METRICS, lambda i: {})


def make_evaluate(mix: octax_core.Env, env_params, eval_envs: int, max_steps: int, act: Callable) -> Callable:
    """`evaluate(act_params, key) -> (returns, ended)`, each (G, eval_envs), jitted: eval_envs
    episodes of each game (env j plays game j mod G), played with `act(act_params, key, (frames,
    game))` until all have ended or `max_steps` steps (an episode cut short keeps its return so far)."""
    num_games = mix.num_games
    n = num_games * eval_envs
    games = lane_games(n, num_games)
    v_reset = jax.vmap(mix.reset, in_axes=(0, None, 0))
    v_step = jax.vmap(mix.step, in_axes=(0, 0, 0, None))

    def evaluate(act_params, key):
        key, reset_key = jax.random.split(key)
        obs, state = v_reset(jax.random.split(reset_key, n), env_params, games)
        carry = (jnp.int32(0), key, obs, state, jnp.zeros(n, jnp.float32), jnp.zeros(n, jnp.bool_))

        def running(carry):
            t, _, _, _, _, ended = carry
            return (t < max_steps) & ~ended.all()

        def body(carry):
            t, key, obs, state, returns, ended = carry
            key, act_key, step_key = jax.random.split(key, 3)
            action = act(act_params, act_key, (obs, state.game))
            obs, state, reward, terminated, truncated, _ = v_step(jax.random.split(step_key, n), state, action,
                                                                   env_params)
            return t + 1, key, obs, state, returns + reward, ended | terminated | truncated

        _, _, _, _, returns, ended = jax.lax.while_loop(running, body, carry)
        # lane j is game j mod G: (n,) -> (eval_envs, G) -> (G, eval_envs)
        return returns.reshape(eval_envs, num_games).T, ended.reshape(eval_envs, num_games).T

    return jax.jit(evaluate, compiler_options=mix.compiler_options)  # the platform's (exact; faster)


def normalized(game: str, value: float) -> float:
    """`scores.normalized_score`, or nan for a game without a reference."""
    try:
        return float(scores.normalized_score(game, value))
    except (ValueError, KeyError, scores.UnknownOptionError):
        return math.nan


def aggregate(normalized_scores: Sequence[float]) -> tuple[float, float]:
    """IQM and mean over the games that have a normalized score (nan if none)."""
    values = np.array([v for v in normalized_scores if np.isfinite(v)], np.float64)
    if not len(values):
        return math.nan, math.nan
    return scores.iqm(values[None, :]), float(values.mean())


# --- the run ------------------------------------------------------------------------------------

def csv_columns(games: Sequence[str]) -> tuple[str, ...]:
    per_game = tuple(f"{kind}_{g}" for g in games for kind in ("return", "std", "norm", "train_return", "train_steps"))
    return (("update", "step", "wall_s", "env_steps_per_s", "iqm_norm", "mean_norm", "train_episode_return",
             "train_episodes", "illegal_actions") + per_game + PPO_METRICS)


def train(config: Config, out_dir, games=None, roms=None, progress: bool = True,
          network: Optional[nn.Module] = None) -> dict:
    """Trains the multi-task agent, evaluating every game as configured; writes config.json,
    progress.csv, learning_curve.png, final.csv and params.msgpack to `out_dir` and, with
    `config.single_baseline`, the single-game agents (`out_dir/single-<game>/`), comparison.csv and
    comparison.png. `games` (ids or `GameSpec`s) and `roms` default to `config.game_list` and the
    ROM store; `network` to `MultiTaskActorCritic` (see `make_train`). Returns a summary: paths, rows, per-game final returns and normalized scores, IQM."""
    config.check()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    mix, env, env_params = make_envs(config, games, roms)
    names = mix.games
    trainer = make_train(config, env, env_params, network)
    eval_steps = config.eval_max_steps or int(np.max(np.asarray(env_params.max_episode_steps)))
    evaluate_policy = make_evaluate(mix, env_params, config.eval_envs, eval_steps, trainer.act)
    evaluate_random = make_evaluate(mix, env_params, config.eval_envs, eval_steps, random_policy(legal_table(mix)))
    (out_dir / "config.json").write_text(json.dumps(
        {"algorithm": "multi-task PPO", "games": list(names), "command": sys.argv, **dataclasses.asdict(config)},
        indent=2, default=str) + "\n")

    train_key, eval_key, random_key = jax.random.split(jax.random.key(config.seed), 3)
    runner = jax.jit(trainer.init)(train_key)
    t0 = time.perf_counter()
    update = jax.jit(trainer.update, donate_argnums=0, compiler_options=mix.compiler_options).lower(runner).compile()
    print(f"compiled the multi-task update in {time.perf_counter() - t0:.1f} s ({len(names)} games, "
          f"{config.num_envs} envs x {config.num_steps} steps, {config.num_updates} updates, "
          f"{config.steps_per_game:,} env steps per game)")
    random_returns, _ = jax.device_get(evaluate_random(None, random_key))
    random_means = random_returns.mean(1)
    print("random policy: " + ", ".join(f"{g} {r:.2f}" for g, r in zip(names, random_means)))

    log = MultiTaskLog(out_dir, names, f"multi-task PPO, {len(names)} games ({config.num_envs} envs"
                       + (", game input)" if config.game_input else ", no game input)"))
    eval_interval = config.num_updates
    if config.eval_every:
        eval_interval = max(1, round(config.eval_every / config.batch_size))
    totals, train_s, start = {}, 0.0, time.perf_counter()
    for i in range(config.num_updates + 1):
        if i % eval_interval == 0 or i == config.num_updates:
            returns, ended = jax.device_get(evaluate_policy(runner.params, jax.random.fold_in(eval_key, i)))
            row = log.add(i, i * config.batch_size, time.perf_counter() - start, train_s, returns, totals)
            if progress:
                print(f"update {i:4d}  steps {row['step']:8d}  IQM {row['iqm_norm']:.3f}  mean {row['mean_norm']:.3f}  "
                      + "  ".join(f"{g} {row[f'return_{g}']:.2f}" for g in names), flush=True)
            totals = {}
        if i == config.num_updates:
            break
        t0 = time.perf_counter()
        runner, metrics = update(runner)
        metrics = jax.device_get(metrics)
        train_s += time.perf_counter() - t0
        for k, v in metrics.items():
            totals[k] = totals.get(k, 0.0) + np.asarray(v, np.float64)
        totals["updates"] = totals.get("updates", 0) + 1

    params_path = out_dir / "params.msgpack"
    params_path.write_bytes(flax.serialization.to_bytes(jax.device_get(runner.params)))
    steps_per_s = config.num_updates * config.batch_size / train_s
    print(f"training speed: {steps_per_s:,.0f} env steps/s, {train_s:.1f} s of updates; "
          f"wall {time.perf_counter() - start:.0f} s")
    final_rows = []
    for g, game in enumerate(names):
        ref = scores.score_table().get(game)
        final_rows.append({"game": game, "random_measured": round(float(random_means[g]), 4),
                           "random_ref": ref.random_mean if ref else math.nan,
                           "reference": ref.reference if ref and ref.reference is not None else math.nan,
                           "eval_return": round(float(returns[g].mean()), 4),
                           "eval_std": round(float(returns[g].std()), 4),
                           "eval_ended_frac": round(float(ended[g].mean()), 4),
                           "normalized": round(normalized(game, float(returns[g].mean())), 4)})
    final_path = _write_csv(out_dir / "final.csv", FINAL_COLUMNS, final_rows)
    iqm_value, mean_value = aggregate([r["normalized"] for r in final_rows])
    print(jax_training_table(final_rows, FINAL_COLUMNS))
    print(f"normalized IQM over {len(names)} games {iqm_value:.3f}, mean {mean_value:.3f}")
    summary = {"csv": log.csv_path, "png": log.png_path, "final_csv": final_path, "params": params_path,
               "rows": log.rows, "final_rows": final_rows, "games": names, "iqm": iqm_value, "mean": mean_value,
               "final_params": runner.params, "env_steps_per_s": steps_per_s, "train_s": train_s}
    if config.single_baseline:
        summary.update(single_baseline(config, out_dir, final_rows, games, roms, progress))
    return summary


def single_baseline(config: Config, out_dir: Path, multi_rows: Sequence[dict], games=None, roms=None,
                    progress: bool = True) -> dict:
    """One PPO agent per game (train_jax_ppo.train), total_steps / G env steps each, evaluated
    like the multi-task agent (eval_envs episodes, sampled actions, the same step cap); writes
    comparison.csv and comparison.png. Returns their paths, rows and the two IQMs."""
    names = [r["game"] for r in multi_rows]
    specs = list(names) if games is None else list(games)
    rows = []
    for g, game in enumerate(names):
        single = single_config(config, game, len(names))
        final_return = _finished_single_run(out_dir / f"single-{game}", single)
        if final_return is None:
            print(f"single-game baseline {g + 1}/{len(names)}: PPO on {game}, {single.num_updates * single.batch_size:,} "
                  f"steps, {single.num_envs} envs", flush=True)
            final_return = ppo.train(single, out_dir / f"single-{game}", game=specs[g],
                                     rom=None if roms is None else roms[g], progress=progress)["final_eval_mean_return"]
        else:
            print(f"single-game baseline {g + 1}/{len(names)}: {game}, reusing {out_dir / f'single-{game}'}")
        multi = multi_rows[g]
        rows.append({"game": game, "steps_per_game": single.num_updates * single.batch_size,
                     "random_ref": multi["random_ref"], "reference": multi["reference"],
                     "multi_return": multi["eval_return"],
                     "single_return": round(final_return, 4),
                     "multi_normalized": multi["normalized"],
                     "single_normalized": round(normalized(game, final_return), 4)})
    multi_iqm, multi_mean = aggregate([r["multi_normalized"] for r in rows])
    single_iqm, single_mean = aggregate([r["single_normalized"] for r in rows])
    table = rows + [{"game": "IQM", "multi_normalized": round(multi_iqm, 4), "single_normalized": round(single_iqm, 4)},
                    {"game": "mean", "multi_normalized": round(multi_mean, 4),
                     "single_normalized": round(single_mean, 4)}]
    table = [{c: r.get(c, "") for c in COMPARISON_COLUMNS} for r in table]
    path = _write_csv(out_dir / "comparison.csv", COMPARISON_COLUMNS, table)
    png = out_dir / "comparison.png"
    _plot_comparison(png, rows, (multi_iqm, single_iqm))
    print(jax_training_table(table, COMPARISON_COLUMNS))
    return {"comparison_csv": path, "comparison_png": png, "comparison_rows": rows,
            "single_iqm": single_iqm, "single_mean": single_mean}


def single_config(config: Config, game: str, num_games: int) -> ppo.Config:
    """The single-game baseline's settings for `game`: the multi-task run's, with total_steps / G
    steps (the multi-task agent's steps per game), `baseline_num_envs` envs and evaluations every
    eval_every / G steps (so at the same steps per game)."""
    num_envs = config.baseline_num_envs or config.num_envs
    return ppo.Config(
        game=game, total_steps=config.steps_per_game, num_envs=num_envs, num_steps=config.num_steps,
        update_epochs=config.update_epochs,
        num_minibatches=min(config.num_minibatches, num_envs * config.num_steps),
        learning_rate=config.learning_rate, anneal_lr=config.anneal_lr, gamma=config.gamma,
        max_grad_norm=config.max_grad_norm, seed=config.seed,
        eval_every=config.eval_every // num_games if config.eval_every else 0, eval_envs=config.eval_envs,
        eval_max_steps=config.eval_max_steps, env_overrides=config.env_overrides, gae_lambda=config.gae_lambda,
        clip_eps=config.clip_eps, clip_value_loss=config.clip_value_loss, vf_coef=config.vf_coef,
        ent_coef=config.ent_coef)


def _finished_single_run(run_dir: Path, single: "ppo.Config") -> Optional[float]:
    """The last evaluation's mean return of a finished single-game run in `run_dir` made with the
    same settings as `single` (config.json), or None: a run to train (none there, or another one)."""
    try:
        saved = json.loads((run_dir / "config.json").read_text())
        rows = list(csv.DictReader(open(run_dir / "progress.csv")))
    except (OSError, ValueError):
        return None
    wanted = json.loads(json.dumps(dataclasses.asdict(single), default=str))
    same = all(saved.get(k) == v for k, v in wanted.items() if k != "env_overrides")
    if not same or not rows or int(rows[-1]["step"]) != single.num_updates * single.batch_size:
        return None
    return float(rows[-1]["eval_mean_return"])


def compare(config: Config, out_dir, games=None, roms=None, progress: bool = True) -> dict:
    """`--compare-only`: the multi-task run already in `out_dir` (its final.csv) against the
    single-game agents (`single_baseline`: those already in `out_dir/single-<game>/` with the
    same settings are read, the others trained)."""
    out_dir = Path(out_dir)
    with open(out_dir / "final.csv") as f:
        rows = [{k: (v if k == "game" else float(v)) for k, v in row.items()} for row in csv.DictReader(f)]
    return single_baseline(config, out_dir, rows, games, roms, progress)


def _write_csv(path: Path, columns: Sequence[str], rows: Sequence[dict]) -> Path:
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, columns)
        writer.writeheader()
        writer.writerows(rows)
    return path


def jax_training_table(rows: Sequence[dict], columns: Sequence[str]) -> str:
    """A plain-text table of `rows`."""
    cells = [[str(r.get(c, "")) for c in columns] for r in rows]
    widths = [max(len(c), *(len(row[k]) for row in cells)) for k, c in enumerate(columns)]
    return "\n".join("  ".join(x.ljust(w) for x, w in zip(line, widths)) for line in [list(columns)] + cells)


def _plot_comparison(path: Path, rows: Sequence[dict], iqms: tuple[float, float]) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = [r["game"] for r in rows] + ["IQM"]
    multi = [r["multi_normalized"] for r in rows] + [iqms[0]]
    single = [r["single_normalized"] for r in rows] + [iqms[1]]
    x = np.arange(len(labels))
    fig, ax = plt.subplots(figsize=(9, 4))
    ax.bar(x - 0.2, multi, 0.4, label="one multi-task agent")
    ax.bar(x + 0.2, single, 0.4, label="one agent per game")
    ax.axhline(0, color="gray", linewidth=0.8)
    ax.axhline(1, color="gray", linestyle=":", linewidth=0.8)
    ax.set_xticks(x, labels, rotation=30)
    ax.set_ylabel("normalized score (0 random, 1 reference)")
    ax.set_title(f"{rows[0]['steps_per_game']:,} env steps per game")
    ax.legend(loc="best", fontsize="small")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


class MultiTaskLog:
    """One CSV row per evaluation (per-game returns and normalized scores, their IQM), and the
    learning curve redrawn each time."""

    def __init__(self, out_dir: Path, games: Sequence[str], title: str):
        self.csv_path, self.png_path = out_dir / "progress.csv", out_dir / "learning_curve.png"
        self.games, self.title, self.rows = tuple(games), title, []
        self.columns = csv_columns(self.games)
        with open(self.csv_path, "w", newline="") as f:
            csv.writer(f).writerow(self.columns)

    def add(self, update: int, step: int, wall_s: float, train_s: float, returns, totals: dict) -> dict:
        """`returns`: (G, eval_envs); `totals`: each metric's sum over the updates since the last evaluation."""
        n = totals.get("updates", 0)
        episodes = float(totals.get("finished_episodes", 0.0))
        row = {"update": update, "step": step, "wall_s": round(wall_s, 2),
               "env_steps_per_s": round(step / train_s, 1) if train_s else math.nan,
               "train_episode_return": float(totals["finished_return_sum"]) / episodes if episodes else math.nan,
               "train_episodes": int(episodes), "illegal_actions": int(totals.get("illegal_actions", 0))}
        norms = []
        for g, game in enumerate(self.games):
            mean = float(np.mean(returns[g]))
            norms.append(normalized(game, mean))
            game_episodes = float(totals["episodes_by_game"][g]) if n else 0.0
            row.update({f"return_{game}": mean, f"std_{game}": float(np.std(returns[g])), f"norm_{game}": norms[-1],
                        f"train_return_{game}": (float(totals["return_sum_by_game"][g]) / game_episodes
                                                 if game_episodes else math.nan),
                        f"train_steps_{game}": int(totals["steps_by_game"][g]) if n else 0})
        row["iqm_norm"], row["mean_norm"] = aggregate(norms)
        for name in PPO_METRICS:
            row[name] = float(totals[name]) / n if n else math.nan
        self.rows.append(row)
        with open(self.csv_path, "a", newline="") as f:
            csv.DictWriter(f, self.columns).writerow(row)
        self._plot()
        return row

    def _plot(self) -> None:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        step = np.array([r["step"] for r in self.rows])
        fig, (ax, raw_ax) = plt.subplots(1, 2, figsize=(12, 4.5))
        for k, game in enumerate(self.games):
            ax.plot(step, [r[f"norm_{game}"] for r in self.rows], ".-", alpha=0.6, linewidth=1, label=game,
                    color=f"C{k % 10}")
        ax.plot(step, [r["iqm_norm"] for r in self.rows], "o-", color="black", linewidth=2.5, label="IQM")
        ax.axhline(0, color="gray", linestyle=":", linewidth=0.8)
        ax.set_xlabel("env steps (all games)")
        ax.set_ylabel("normalized score (0 random, 1 reference)")
        ax.set_title(self.title, fontsize="medium")
        ax.legend(loc="best", fontsize="x-small", ncol=2)
        for k, game in enumerate(self.games):
            raw_ax.plot(step, [r[f"return_{game}"] for r in self.rows], ".-", label=game, color=f"C{k % 10}")
        raw_ax.set_xlabel("env steps (all games)")
        raw_ax.set_ylabel("eval episode return")
        raw_ax.set_title("per-game evaluation return", fontsize="medium")
        fig.tight_layout()
        fig.savefig(self.png_path, dpi=100)
        plt.close(fig)


# --- command line -------------------------------------------------------------------------------

HELP = {
    **ppo.HELP,
    "game": "names the default --out-dir only (the games are --games)",
    "games": "the games of the mix (one platform), comma- or space-separated",
    "total_steps": "env steps over all envs and games (total_steps / G per game)",
    "num_envs": "parallel training envs, a multiple of the number of games (env i plays game i mod G)",
    "num_seeds": "must be 1: one seed per run",
    "eval_every": "env steps (all games) between evaluations; 0: only at the start and the end",
    "eval_envs": "evaluation episodes per game, played to their end",
    "eval_max_steps": "step cap per evaluation; None: the longest max_episode_steps of the games",
    "game_input": "give the network the game's one-hot (beside the CNN features)",
    "redraw_games": "draw each new episode's game uniformly (the mix's autoreset) instead of fixed lanes",
    "single_baseline": "then train one PPO agent per game for total_steps / G steps and write comparison.csv",
    "baseline_num_envs": "envs of each single-game agent; 0: num_envs",
    "compare_only": "no training: compare --out-dir's finished multi-task run with the single-game agents "
                    "(finished ones in out-dir/single-<game> with the same settings are reused, others trained)",
}


def _join_games(argv: Sequence[str]) -> list[str]:
    """`--games A B C` -> `--games A,B,C` (the flag also takes the comma-separated form)."""
    out, i = [], 0
    argv = list(argv)
    while i < len(argv):
        if argv[i] == "--games":
            j = i + 1
            while j < len(argv) and not argv[j].startswith("-"):
                j += 1
            out += ["--games", ",".join(argv[i + 1:j])]
            i = j
        else:
            out.append(argv[i])
            i += 1
    return out


def main(argv: Optional[Sequence[str]] = None) -> dict:
    """The command line (flags: one per `Config` field, as the other examples), training, summary."""
    argv = sys.argv[1:] if argv is None else argv
    config, out_dir = jax_training.parse_args(Config, HELP, __doc__.split("\n\n")[0], "runs/jax_multitask",
                                              _join_games(argv))
    print(f"multi-task PPO on {', '.join(config.game_list)}: {config}")
    if config.compare_only:
        summary = compare(config, out_dir)
        print(f"wrote {summary['comparison_csv']} and {summary['comparison_png']}")
        return summary
    summary = train(config, out_dir)
    print(f"wrote {summary['csv']}, {summary['png']} and {summary['final_csv']}"
          + (f", {summary['comparison_csv']}" if "comparison_csv" in summary else ""))
    return summary


if __name__ == "__main__":
    main(sys.argv[1:])
