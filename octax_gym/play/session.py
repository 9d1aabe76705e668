"""One game being played: the real env (`OctaxVectorEnv` or, for a two-player game,
`MultiAgentVectorEnv`, a batch of one), who plays each seat, the keys held, and the episode.

The server (`octax_gym.play.server`) calls `reset()` and `step()` on its clock; everything here is
synchronous and knows nothing of the web. A step's frames are sent as palette indices (0 dark, 1
lit, 2 and 3 XO-CHIP's other planes), which the page draws in the game's palette.

Episode e (from 0) of a session seeded s is reset with seed (s + e) mod 2**32, exactly as
`OctaxEnv.reset(seed=...)` resets with that seed: the seed (each frame message carries it) and the
actions the server logs replay it. The env takes seeds 0..2**32 - 1 (they become uint32 PRNG seeds),
and a session may play any number of episodes, so the count wraps instead of running off the end.
"""

from __future__ import annotations

import base64
import collections
import dataclasses
import time
from typing import Any, Callable, Optional

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.env.games import list_games
from octax_core.env.players import make_player
from octax_gym.envs import render
from octax_gym.envs.game_names import resolve_spec
from octax_gym.envs.multi_vector import MultiAgentVectorEnv
from octax_gym.envs.vector import FRAMES_PER_SECOND, OctaxVectorEnv
from octax_gym.play.protocol import TABLE_PLAYERS
from octax_gym.step.compiled_step import MAX_SEED

# Octo's keyboard layout: the keys of a 4x4 block on a QWERTY keyboard, row by row, are the
# COSMAC VIP's hex keypad 1 2 3 C / 4 5 6 D / 7 8 9 E / A 0 B F.
KEYBOARD = {"1": 0x1, "2": 0x2, "3": 0x3, "4": 0xC,
            "q": 0x4, "w": 0x5, "e": 0x6, "r": 0xD,
            "a": 0x7, "s": 0x8, "d": 0x9, "f": 0xE,
            "z": 0xA, "x": 0x0, "c": 0xB, "v": 0xF}
KEY_OF_CHIP8 = {chip8: key for key, chip8 in KEYBOARD.items()}
Agent = Callable[[np.ndarray], int]  # one seat's observation (C, H, W) -> an action
HISTORY = 100_000                    # steps of (episode, step, actions, seq) kept for tests and tools


def is_two_player(game: Any) -> bool:
    return resolve_spec(game).id in list_games(players=2)


def check_seed(seed: Any) -> int:
    """The seed as an int, or a ValueError naming the range the env takes (uint32 PRNG seeds)."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed < MAX_SEED:
        raise ValueError(f"seed must be an int in 0..{MAX_SEED - 1} (the env's seeds are uint32), got {seed!r}")
    return int(seed)


def episode_seed(seed: int, episode: int) -> int:
    """Episode `episode`'s reset seed in a session seeded `seed`: seed + episode, wrapped into the env's range."""
    return (seed + episode) % MAX_SEED


@dataclasses.dataclass
class StepRecord:
    """What one step was: its episode, seed and step number, the actions of each seat, and the
    last key event the step had seen."""

    episode: int
    seed: int
    step: int
    actions: tuple[int, ...]
    seq: int


class Session:
    """A game, its seats and the episode in play.

    Args:
        game: a game id ("Brix", "Duel"), Gymnasium id, any case, or a `GameSpec` (with `rom=`
            in `env_options` for a ROM file: `octax_gym.cli.common.game_or_rom`).
        seed: the first episode's seed, 0..2**32 - 1; episode e is seeded (seed + e) mod 2**32.
        agent: a function of one seat's observation -> action (`octax_gym.play.agents`), or None.
        players: each seat's player ("human", "agent", "scripted", "random"); default: a human
            in seat 0, the agent if there is one else "human" for one player; for two, seat 1
            the agent if there is one, else the scripted player, else random.
        recorder: an `octax_gym.play.record.Recorder` for the human's episodes, or None.
        env_options: the env's options (max_episode_steps, ...).
    """

    def __init__(self, game: Any, *, seed: int = 0, agent: Optional[Agent] = None,
                 players: Optional[list[str]] = None, recorder=None, **env_options):
        seed = check_seed(seed)  # before anything is compiled
        self.spec = resolve_spec(game)
        self.two_player = is_two_player(self.spec)
        cls = MultiAgentVectorEnv if self.two_player else OctaxVectorEnv
        self.env = cls(self.spec, 1, autoreset_mode="disabled", **env_options)  # the spec: a ROM file's too
        self.env_options = env_options
        core = self.env.core_env
        self.frames_per_step = core.config.frames_per_step
        self.height, self.width = core.observation_shape[-2:]
        self.num_actions = core.num_actions
        self.obs_scale = core.config.obs_scale
        self.xo = core.machine.platform.planes > 1
        self.palette = self.env.palette
        self.seats = 2 if self.two_player else 1
        self.seat_keys = (tuple(self.spec.seats.action_keys) if self.two_player else (tuple(self.spec.action_keys),))
        self.seat_names = tuple(self.spec.seats.names) if self.two_player else ("player",)
        self.turn_based = bool(getattr(core, "turn_based", False))
        self.scripted_available = bool(self.two_player and self.spec.seats.scripted_policy is not None)
        self.agent = agent
        self.players = list(players or self.default_players())
        for seat, player in enumerate(self.players):
            self.check_player(seat, player)
        self.recorder = recorder
        self.seed0 = seed
        self.episode = -1
        self.held: list[int] = []          # CHIP-8 keys held, the latest pressed last
        self.seq = 0                       # the last key event seen
        self.draws = jax.random.key(seed)  # the table players' draws (random), one a step
        self.history: collections.deque[StepRecord] = collections.deque(maxlen=HISTORY)
        self.step_times: collections.deque[float] = collections.deque(maxlen=151)
        self.step_seconds: collections.deque[float] = collections.deque(maxlen=150)
        # Seconds from a key press reaching the server to the end of the step that played it.
        self.key_wait: collections.deque[float] = collections.deque(maxlen=1000)
        self._pressed_at: Optional[float] = None
        self._table = {}                   # a table player's name -> its compiled action
        self.obs = self.info = None
        self.done = False
        self.human_only = True             # every step of this episode was played by humans alone
        self._warm_up()
        self.reset()
        for name in TABLE_PLAYERS:          # compiled now, not in the middle of a game
            if name in self.available_players():
                self._table_action(name, 0)

    def _warm_up(self) -> None:
        """Compiles the env's reset, step and masked reset now, not in the middle of a game."""
        noop = np.zeros((1, self.seats) if self.two_player else (1,), np.int32)
        self.env.reset(seed=self.seed0)
        self.env.step(noop)
        self.env.reset(seed=self.seed0, options={"reset_mask": np.ones(1, np.bool_)})
        self.env.step(noop)

    # --- players ---------------------------------------------------------------------------

    def default_players(self) -> list[str]:
        if not self.two_player:
            return ["agent" if self.agent is not None else "human"]
        other = "agent" if self.agent is not None else ("scripted" if self.scripted_available else "random")
        return ["human", other]

    def available_players(self) -> list[str]:
        players = ["human"]
        if self.agent is not None:
            players.append("agent")
        if self.scripted_available:
            players.append("scripted")
        return players + ["random"]

    def check_player(self, seat: int, player: str) -> None:
        if seat >= self.seats:
            raise ValueError(f"{self.spec.id} has {self.seats} seat(s); no seat {seat}")
        if player not in self.available_players():
            raise ValueError(f"player {player!r} is not available for {self.spec.id}; "
                             f"available: {', '.join(self.available_players())}")

    def set_player(self, seat: int, player: str) -> None:
        self.check_player(seat, player)
        self.players[seat] = player

    # --- keys ------------------------------------------------------------------------------

    def key(self, key: int, down: bool, seq: Optional[int] = None) -> None:
        if key in self.held:
            self.held.remove(key)
        if down:
            self.held.append(key)
        if seq is not None and seq > self.seq:
            self.seq = seq
            if down:
                self._pressed_at = time.perf_counter()

    def human_action(self, seat: int) -> int:
        """The action of the latest-pressed held key among the seat's keys, else 0 (no key)."""
        keys = self.seat_keys[seat]
        for key in reversed(self.held):
            if key in keys:
                return keys.index(key) + 1
        return 0

    # --- the env ---------------------------------------------------------------------------

    @property
    def seed(self) -> int:
        return episode_seed(self.seed0, self.episode)

    def reset(self) -> dict:
        """Ends the episode in play (the recorder keeps it if a human played it) and starts the
        next; the episode count moves only once the env has reset."""
        self._finish(cut=True)
        options = None if self.obs is None else {"reset_mask": np.ones(1, np.bool_)}
        self.obs, self.info = self.env.reset(seed=episode_seed(self.seed0, self.episode + 1), options=options)
        self.episode += 1
        self.done = False
        self.step_count = 0
        self.returns = np.zeros(self.seats, np.float64)
        self.last_reward = np.zeros(self.seats, np.float64)
        self.last_actions = (0,) * self.seats
        self.human_only = all(player == "human" for player in self.players)
        if self.recorder is not None:
            self.recorder.start(self.seed, self.obs[0], self._info_row())
        return self.message()

    def step(self) -> dict:
        """One env step with every seat's action; returns the frame message. After the episode's
        end it does nothing (the page asks for a reset)."""
        if self.done:
            return self.message()
        start = time.perf_counter()
        actions = tuple(self._action(seat) for seat in range(self.seats))
        if any(player != "human" for player in self.players):
            self.human_only = False
        batch = np.array([actions if self.two_player else actions[0]], np.int32)
        self.obs, reward, terminated, truncated, self.info = self.env.step(batch)
        reward = np.asarray(reward[0], np.float64).reshape(self.seats)
        self.step_count += 1
        self.returns += reward
        self.last_reward = reward
        self.last_actions = actions
        self.done = bool(terminated[0] or truncated[0])
        self.history.append(StepRecord(self.episode, self.seed, self.step_count, actions, self.seq))
        if self.recorder is not None:
            self.recorder.add(actions[0], self.obs[0], float(reward[0]), bool(terminated[0]), bool(truncated[0]),
                              self._info_row())
        if self.done:
            self._finish(cut=False)
        now = time.perf_counter()
        if self._pressed_at is not None:
            self.key_wait.append(now - self._pressed_at)
            self._pressed_at = None
        self.step_seconds.append(now - start)
        self.step_times.append(now)
        return self.message()

    def _action(self, seat: int) -> int:
        player = self.players[seat]
        if player == "human":
            action = self.human_action(seat)
        elif player == "agent":
            action = int(self.agent(self.seat_observation(seat)))
        else:
            action = self._table_action(player, seat)
        if not 0 <= action < self.num_actions or not self.legal_mask(seat)[action]:
            action = 0  # a key the game does not take now (a turn-based game's other turn) holds none
        return action

    def legal_mask(self, seat: int) -> np.ndarray:
        if not self.two_player:
            return np.ones(self.num_actions, np.bool_)
        return np.asarray(self.info["legal_action_mask"])[0, seat]

    def seat_observation(self, seat: int) -> np.ndarray:
        """What an agent in `seat` sees: (F, H, W) in a one-player game, (F + 1, H, W) in a two-player one."""
        return np.asarray(self.obs[0, seat] if self.two_player else self.obs[0])

    def _table_action(self, name: str, seat: int) -> int:
        """The action of the table's player `name` (`octax_core.env.players`) in `seat`, from the
        env's state, the seat's observation and legal actions, and the session's next key."""
        if name not in self._table:
            player = make_player(name, self.spec if self.two_player else None,
                                 self.two_player and self.env.core_env.mirrored)
            self._table[name] = jax.jit(jax.vmap(player, in_axes=(None, 0, 0, 0, None, 0)))
        self.draws, draw = jax.random.split(self.draws)
        obs = self.obs[:, seat] if self.two_player else self.obs
        action = self._table[name](None, draw[None], jnp.asarray(obs), self.env.state, jnp.int32(seat),
                                   jnp.asarray(self.legal_mask(seat))[None])
        return int(action[0])

    def _finish(self, cut: bool) -> None:
        if self.recorder is not None and self.obs is not None:
            self.recorder.finish(cut=cut, keep=self.human_only)

    def _info_row(self) -> dict:
        return {name: np.asarray(value)[0] for name, value in self.info.items()
                if not name.startswith("_") and name in ("score", "lives", "episode_step")}

    # --- what the page gets ----------------------------------------------------------------

    def frames(self) -> np.ndarray:
        """The step's frames as palette indices, uint8 (F, H, W)."""
        frames = np.asarray(self.obs[0, 0, :self.frames_per_step] if self.two_player else self.obs[0])
        if self.obs_scale == 1:
            return frames.astype(np.uint8)
        return (frames // (85 if self.xo else 255)).astype(np.uint8)

    def message(self) -> dict:
        score = np.asarray(self.info["score"])[0].reshape(-1)
        lives = int(np.asarray(self.info["lives"])[0])
        return {"type": "frame", "episode": self.episode, "seed": self.seed, "step": self.step_count,
                "frames": base64.b64encode(self.frames().tobytes()).decode("ascii"),
                "score": [int(s) for s in score], "lives": lives, "reward": self.last_reward.tolist(),
                "return": self.returns.tolist(), "actions": list(self.last_actions), "seq": self.seq,
                "done": self.done, "fps": round(self.frames_per_second(), 1)}

    def hello(self) -> dict:
        """The game's description for the page."""
        actions = []
        for seat, keys in enumerate(self.seat_keys):
            actions.append([{"action": i + 1, "chip8": key, "keyboard": KEY_OF_CHIP8[key].upper()}
                            for i, key in enumerate(keys)])
        return {"type": "hello", "game": self.spec.id, "title": self.spec.title,
                "description": self.spec.description, "platform": self.spec.platform,
                "width": self.width, "height": self.height, "frames_per_step": self.frames_per_step,
                "frames_per_second": FRAMES_PER_SECOND, "palette": self.palette.tolist(),
                "keyboard": KEYBOARD, "seats": [{"name": name, "actions": actions[seat]}
                                                for seat, name in enumerate(self.seat_names)],
                "players": self.available_players(), "recording": self.recorder is not None,
                "turn_based": self.turn_based}

    def frames_per_second(self) -> float:
        """Frames a second over the last (up to) 150 steps: steps/s x frames_per_step."""
        if len(self.step_times) < 2:
            return 0.0
        span = self.step_times[-1] - self.step_times[0]
        return (len(self.step_times) - 1) * self.frames_per_step / span if span > 0 else 0.0

    def close(self) -> None:
        self._finish(cut=True)
        self.obs = None
        self.env.close()


def palette_rgb(indices: np.ndarray, palette: np.ndarray, scale: int = 1) -> np.ndarray:
    """Palette indices (H, W) -> RGB, as the page draws them (for tests and screenshots)."""
    return render.to_rgb(indices, scale, palette)
