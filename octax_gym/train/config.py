"""What a training run depends on, in one frozen dataclass (`TrainConfig`), checked once.

Every field is a setting of the command line (`octax-gym train`, one flag per field) and is written
to the run's config.json, so a run can be repeated or resumed from its folder alone. The
algorithm's own settings (PPO's clip, PQN's lambda) are fields too: one flat record reads and
resumes more simply than nested ones, and `check` refuses a setting that does nothing.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Optional, Union

from octax_core.env.games import GameSpec
from octax_core.env.mix import MIXES

ALGORITHMS = ("ppo", "pqn", "multitask", "selfplay", "bc", "cql")  # multitask: one PPO agent per seed over all
# the games; selfplay: one PPO agent per seed on both seats of a two-player game (seats.py, selfplay.py)
OFFLINE = ("bc", "cql")  # trained on a Minari dataset instead of a rollout (offline.py)
DEVICES = ("", "all")
ARCHIVE = "archive:"  # in games: archive:DIR[:SPLIT|:NAME], an `octax-gym generate` archive's games
AGENT_MAPS = ("auto", "vmap", "map")
NETWORK_LAYOUTS = ("image", "paper")  # how the conv torso reads the frames (networks.ConvTorso)
ENV_FLAGS = {"max_episode_steps": int, "frames_per_step": int, "repeat_action_probability": float,
             "noop_max": int,  # octax_core.make options a run may override (for every game alike)
             "mirror": bool}  # make_multi's: selfplay's seat 1 sees and plays the mirror image (--mirror)


@dataclasses.dataclass(frozen=True)
class TrainConfig:
    """Settings of one run of G games x S seeds; defaults are the paper's PPO (`presets.PAPER`).

    `games` and `seed`..`seed + num_seeds - 1` make G x S independent agents, trained at once;
    steps, envs and evaluations are per agent.
    """

    algorithm: str = "ppo"
    games: tuple = ("Brix",)  # game ids (or GameSpecs, from Python); "octax16" expands to the paper's 16
    seed: int = 0
    num_seeds: int = 1
    total_steps: int = 5_000_000  # env steps per agent
    num_envs: int = 512  # training envs per agent
    num_steps: int = 32  # rollout length per env and update
    update_epochs: int = 4
    num_minibatches: int = 32
    learning_rate: float = 5e-4
    anneal_lr: bool = False  # the paper names no schedule; its code passes a constant rate to Adam
    gamma: float = 0.99
    max_grad_norm: float = 0.5
    eval_every: int = 131_072  # env steps per agent between evaluations; 0: at the start and the end only
    eval_envs: int = 128  # evaluation episodes per agent and policy (one per env)
    eval_max_steps: Optional[int] = None  # step cap per evaluation; None: the game's max_episode_steps
    eval_noop_max: int = 30  # evaluation episodes start after 0..30 no-ops (the ALE protocol), see evaluate.py
    checkpoint_every: int = 0  # updates between resumable checkpoints; 0: none
    save_at_evals: bool = False  # keep every evaluation's agents too (agents/<name>-step<N>.msgpack): medium policies
    devices: str = ""  # "": one device; "all": every agent's envs split over every device
    agent_map: str = "auto"  # how agents share the program: vmap, map (one after another), auto (many.py)
    network_layout: str = "image"  # the torso's layout (networks.LAYOUTS): the paper's text, or "paper", its code's
    env_overrides: tuple = ()  # ((name, value), ...) of ENV_FLAGS, for every game
    eval_games: tuple = ()  # games every agent is evaluated on too but never trains on (held-out variants)
    # PPO's
    gae_lambda: float = 0.95
    clip_eps: float = 0.2
    clip_value_loss: bool = True  # CleanRL's Atari PPO and the paper's Rejax-based code clip it
    vf_coef: float = 0.5
    ent_coef: float = 0.01
    ent_coef_final: Optional[float] = None  # the entropy weight decays linearly to it over the run; None: constant
    # PQN's
    q_lambda: float = 0.9
    epsilon_start: float = 1.0
    epsilon_finish: float = 0.05
    epsilon_fraction: float = 0.1  # of total_steps, over which epsilon decays linearly
    eval_epsilon: float = 0.005  # the sampled evaluation of PQN: epsilon-greedy (the paper's code)
    # multitask's
    game_input: bool = True  # the game's one-hot joins the torso's features (else the screen alone tells)
    # selfplay's
    pool: int = 0  # K past selves (one snapshot per evaluation) as opponents; 0: pure self-play
    pool_prob: float = 0.5  # per env and update, the chance that one seat is played by a drawn past self
    eval_opponents: tuple = ("random", "eps0.5", "scripted")  # the evaluation's matches: players of
    # octax_core.env.players (the ladder's rungs among them), weakest first; one the game lacks: nan cells
    # offline (bc, cql)
    dataset: str = ""  # the Minari dataset id trained on; the run's game and env options are the dataset's
    cql_alpha: float = 1.0  # weight of CQL's regulariser
    target_every: int = 64  # CQL: updates between copies of the target network

    @property
    def batch_size(self) -> int:
        return self.num_envs * self.num_steps

    @property
    def num_updates(self) -> int:
        return max(1, self.total_steps // self.batch_size)

    @property
    def eval_interval(self) -> int:
        """Updates between evaluations (and self-play's pool snapshots); the last update is evaluated too."""
        if not self.eval_every:
            return self.num_updates
        return max(1, round(self.eval_every / self.batch_size))

    @property
    def seeds(self) -> list[int]:
        return [self.seed + i for i in range(self.num_seeds)]

    @property
    def game_ids(self) -> list[str]:
        return [game.id if isinstance(game, GameSpec) else game for game in self.games]

    @property
    def eval_game_ids(self) -> list[str]:
        return [game.id if isinstance(game, GameSpec) else game for game in self.eval_games]

    @property
    def multitask(self) -> bool:
        return self.algorithm == "multitask"

    @property
    def selfplay(self) -> bool:
        return self.algorithm == "selfplay"

    @property
    def agents(self) -> list[tuple[str, int]]:
        """(game, seed) of each row of the log (an evaluation of one game by one agent), game-major,
        the `eval_games` after the trained games. One agent per row, except in a multi-task run,
        where the agent of a seed plays every game, and in a run with `eval_games`, where it plays those too."""
        return [(game, seed) for game in self.game_ids + self.eval_game_ids for seed in self.seeds]

    @property
    def agent_names(self) -> list[str]:
        """The trained agents, in the order of the agent axis: `<game>-seed<s>`, or `multitask-seed<s>`."""
        if self.multitask:
            return [f"multitask-seed{seed}" for seed in self.seeds]
        return [f"{game}-seed{seed}" for game in self.game_ids for seed in self.seeds]

    def agent_view(self, planes: int) -> dict:
        """What the saved agents' files record of how they see their game (`jax_policy.VIEW_KEYS`),
        for agents that read `planes` input planes: {"mirror": True} for a --mirror run, and
        {"layout": "paper", "planes": planes} for the paper's layout, whose params do not show how
        many frames it reads; nothing for the default (the files hold their params alone)."""
        view = {"mirror": True} if dict(self.env_overrides).get("mirror", False) else {}
        if self.network_layout != "image":
            view.update(layout=self.network_layout, planes=int(planes))
        return view

    @property
    def row_agents(self) -> list[int]:
        """For each row of `agents`, the index of the agent that plays it."""
        if self.multitask or self.eval_games:  # with eval_games a ppo or pqn run trains one game (check)
            return [i for _ in self.agents[::self.num_seeds] for i in range(self.num_seeds)]
        return list(range(len(self.agents)))

    @property
    def row_splits(self) -> list[str]:
        """For each row of `agents`: "train" (a game the agent trains on) or "eval" (one of `eval_games`)."""
        trained = len(self.game_ids) * self.num_seeds
        return ["train" if i < trained else "eval" for i in range(len(self.agents))]

    def learning_rate_at(self, update: int) -> float:
        """Adam's rate during update `update` (from 0): constant, or decaying linearly to 0 with `anneal_lr`."""
        if not self.anneal_lr:
            return self.learning_rate
        return self.learning_rate * max(0.0, 1.0 - update / self.num_updates)

    def ent_coef_at(self, update: Any) -> Any:
        """PPO's entropy weight in update `update` (from 0): `ent_coef`, or with `ent_coef_final` linear
        from `ent_coef` to it over the run (a policy that starts curious and ends nearly greedy)."""
        if self.ent_coef_final is None:
            return self.ent_coef
        import jax.numpy as jnp

        progress = jnp.minimum(1.0, jnp.asarray(update, jnp.float32) / self.num_updates)
        return self.ent_coef + (self.ent_coef_final - self.ent_coef) * progress

    def epsilon(self, update: Any) -> Any:
        """PQN's exploration rate in update `update`: linear in the env steps done before it, from
        epsilon_start to epsilon_finish at epsilon_fraction of the run, then constant."""
        import jax.numpy as jnp

        decay_steps = max(1.0, self.epsilon_fraction * self.num_updates * self.batch_size)
        progress = jnp.minimum(1.0, jnp.asarray(update, jnp.float32) * self.batch_size / decay_steps)
        return self.epsilon_start + (self.epsilon_finish - self.epsilon_start) * progress

    def check(self) -> "TrainConfig":
        """Raises ValueError naming the first setting no run can use; returns the config."""
        _choice("algorithm", self.algorithm, ALGORITHMS)
        _choice("devices", self.devices, DEVICES)
        _choice("agent_map", self.agent_map, AGENT_MAPS)
        _choice("network_layout", self.network_layout, NETWORK_LAYOUTS)
        if not self.games:
            raise ValueError("games must name at least one game (comma-separated ids, or octax16)")
        if len(set(self.game_ids)) != len(self.game_ids):
            raise ValueError(f"games names a game twice: {', '.join(self.game_ids)}")
        for name in ("num_seeds", "num_envs", "num_steps", "update_epochs", "num_minibatches", "eval_envs",
                     "total_steps"):
            _at_least(name, getattr(self, name), 1)
        for name in ("seed", "eval_every", "checkpoint_every", "eval_noop_max"):
            _at_least(name, getattr(self, name), 0)
        if self.eval_max_steps is not None:
            _at_least("eval_max_steps", self.eval_max_steps, 1)
        if self.batch_size % self.num_minibatches:
            raise ValueError(f"num_envs * num_steps = {self.batch_size} is not divisible by "
                             f"num_minibatches = {self.num_minibatches}")
        if self.total_steps < self.batch_size:
            raise ValueError(f"total_steps = {self.total_steps} is less than one update "
                             f"(num_envs * num_steps = {self.batch_size})")
        for name in ("learning_rate", "max_grad_norm"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)}")
        for name in ("gamma", "gae_lambda", "q_lambda", "epsilon_start", "epsilon_finish", "epsilon_fraction",
                     "eval_epsilon", "pool_prob"):
            if not 0 <= getattr(self, name) <= 1:
                raise ValueError(f"{name} must be in [0, 1], got {getattr(self, name)}")
        for name, value in self.env_overrides:
            _choice("env override", name, tuple(ENV_FLAGS))
        if self.algorithm in OFFLINE:
            if not self.dataset:
                raise ValueError(f"{self.algorithm} trains on a dataset: give its Minari id (--dataset, e.g. "
                                 "octax/Flak/expert-v0)")
            if len(self.games) != 1:
                raise ValueError(f"{self.algorithm} trains on one dataset, of one game; got games "
                                 f"{', '.join(self.game_ids)}")
            if self.devices:
                raise ValueError(f"devices must be '' for {self.algorithm} (one device: the dataset lies on it)")
        elif self.dataset:
            raise ValueError(f"dataset is a setting of bc and cql, not of {self.algorithm}")
        _at_least("target_every", self.target_every, 1)
        if not self.cql_alpha >= 0:
            raise ValueError(f"cql_alpha must be >= 0, got {self.cql_alpha}")
        _at_least("pool", self.pool, 0)
        if self.pool and not self.selfplay:
            raise ValueError(f"pool is a setting of selfplay, not of {self.algorithm}")
        mirror = dict(self.env_overrides).get("mirror", False)
        if mirror and not self.selfplay:
            raise ValueError(f"mirror is a setting of selfplay (a two-player game's seats), not of {self.algorithm}")
        if self.ent_coef_final is not None:
            if self.algorithm not in ("ppo", "multitask", "selfplay"):
                raise ValueError(f"ent_coef_final is a setting of PPO (ppo, multitask, selfplay), not of "
                                 f"{self.algorithm}")
            if isinstance(self.ent_coef_final, bool) or not self.ent_coef_final >= 0:
                raise ValueError(f"ent_coef_final must be >= 0, got {self.ent_coef_final!r}")
        if not self.selfplay and self.eval_opponents != TrainConfig.eval_opponents:
            raise ValueError(f"eval_opponents is a setting of selfplay, not of {self.algorithm}")
        if self.selfplay:
            if len(self.games) != 1:
                raise ValueError(f"selfplay trains on one two-player game; got games {', '.join(self.game_ids)}")
            from octax_core.env.games import get_spec, list_games

            spec = self.games[0] if isinstance(self.games[0], GameSpec) else get_spec(self.games[0])
            if spec.seats is None:
                raise ValueError(f"selfplay: {spec.id} is a one-player game; two-player games: "
                                 f"{', '.join(list_games(players=2))}")
            if self.eval_envs % 2:
                raise ValueError(f"selfplay: eval_envs = {self.eval_envs} must be even (half the evaluation games "
                                 "from each seat)")
            if self.devices:
                raise ValueError("devices must be '' for selfplay (its two-seat envs run on one device)")
            if mirror and (spec.seats.mirror is None):
                from octax_core.env.config import mirrored_games

                raise ValueError(f"selfplay: {spec.id} has no mirrored seats (Seats.mirror); mirror is for "
                                 f"{', '.join(mirrored_games())}")
            from octax_core.env.players import check_player

            if not self.eval_opponents:
                raise ValueError("selfplay: eval_opponents must name at least one player (e.g. random,eps0.5,scripted)")
            for name in self.eval_opponents:
                check_player(name)  # any game's name (the message lists them); one the game lacks gives nan cells
            if len(set(self.eval_opponents)) != len(self.eval_opponents):
                raise ValueError(f"selfplay: eval_opponents names a player twice: {', '.join(self.eval_opponents)}")
        if self.eval_games:
            self._check_eval_games()
        if self.multitask and self.num_envs % len(self.games):
            raise ValueError(f"multitask: num_envs = {self.num_envs} must be a multiple of the {len(self.games)} "
                             "games (lane i plays game i mod G, so each game gets as many lanes)")
        return self

    def _check_eval_games(self) -> None:
        if self.algorithm not in ("ppo", "pqn", "multitask"):
            raise ValueError(f"eval_games is a setting of ppo, pqn and multitask, not of {self.algorithm}")
        ids = self.eval_game_ids
        if len(set(ids)) != len(ids):
            raise ValueError(f"eval_games names a game twice: {', '.join(ids)}")
        if both := [game for game in ids if game in self.game_ids]:
            raise ValueError(f"eval_games: {', '.join(both)} also trained on (games); eval_games are games the "
                             "agents never train on")
        if not self.multitask and len(self.games) != 1:
            raise ValueError(f"eval_games: a {self.algorithm} run with eval_games trains one game (its rows are "
                             f"keyed by game and seed); got games {', '.join(self.game_ids)}: one run per game")
        if self.multitask and self.game_input:
            raise ValueError("eval_games: a multitask agent with game_input reads its game's one-hot, which a game "
                             "it never trained on has none of; give --no-game-input (the screen alone)")


def resolve_games(games: Union[str, tuple, list]) -> tuple:
    """Game ids from a comma-separated string or a list; a named mix ("octax16", `octax_core`'s
    `MIXES`: the paper's 16 games) expands to its games, and `archive:DIR[:SPLIT]` to the GameSpecs of
    an `octax-gym generate` archive (`octax_gym.generated.load_archive`: its accepted games, of
    SPLIT "train" or "test", or both; `archive:DIR:NAME`, the one game NAME). Gymnasium ids and
    any-case names are taken (`octax_gym.envs.game_names`).

    Raises:
        UnknownOptionError: a name that is no registered game (the message lists the valid ones).
        ValueError: an archive that is not there, or an unknown split (`load_archive`'s messages).
    """
    from octax_gym.envs.game_names import resolve_spec

    names = [g.strip() for g in games.split(",")] if isinstance(games, str) else list(games)
    out: list = []
    for name in names:
        if isinstance(name, GameSpec):
            out.append(name)
        elif name in MIXES:
            out.extend(MIXES[name])
        elif name.startswith(ARCHIVE):
            out.extend(_archive_games(name[len(ARCHIVE):]))
        elif name:
            out.append(resolve_spec(name).id)
    return tuple(out)


def _archive_games(text: str) -> list:
    """`DIR[:SPLIT]` or `DIR:NAME` (one game of the archive)'s GameSpecs; a last part that is
    neither is part of the folder's path."""
    from pathlib import Path

    from octax_core.generate.archive import SPLITS
    from octax_gym.generated import load_archive

    folder, _, part = text.rpartition(":")
    if part in SPLITS or not text:
        if not folder:
            raise _no_folder(text)
        return load_archive(folder, part)
    if folder and (Path(folder).expanduser() / "archive.json").is_file():
        games = load_archive(folder)
        chosen = [spec for spec in games if spec.id == part]
        if not chosen:
            raise ValueError(f"{ARCHIVE}{text}: {part!r} is no split (train, test) and no accepted game of "
                             f"{folder}; its games: {', '.join(spec.id for spec in games)}")
        return chosen
    return load_archive(text)


def _no_folder(text: str) -> ValueError:
    return ValueError(f"{ARCHIVE}{text}: name the archive's folder ({ARCHIVE}DIR, {ARCHIVE}DIR:train, "
                      f"{ARCHIVE}DIR:test or {ARCHIVE}DIR:NAME, one of its games)")


def _choice(name: str, value, choices) -> None:
    if value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(repr(c) for c in choices)}, got {value!r}")


def _at_least(name: str, value, minimum: int) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise ValueError(f"{name} must be an int >= {minimum}, got {value!r}")
