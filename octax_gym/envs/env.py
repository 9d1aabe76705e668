"""`OctaxEnv`: one game (CHIP-8, SUPER-CHIP or XO-CHIP) as a `gymnasium.Env`, behind `gymnasium.make`.

It runs the same compiled env step as `OctaxVectorEnv` with a batch of one, so a single env
seeded s and row i of a vector env seeded s - i play the same game step for step. For many envs
use `gymnasium.make_vec`: one batched call is far faster than many single envs.

A two-player game is one seat against a fixed opponent with `opponent=` (and `seat=`):
`gymnasium.make("octax/SpaceRacer-v0", opponent="scripted")`; see `octax_gym.step.opponent`.

What a Gymnasium or ale-py user reaches for works as there: `env.spec.max_episode_steps` is where
episodes are cut, `env.unwrapped.get_action_meanings()` names the actions, and
`render_mode="human"` is refused when the env is made, with the ways to watch a game instead
(this env opens no window; Gymnasium's fallback, a pygame window, would fail only at `reset`).
"""

from __future__ import annotations

import dataclasses
from typing import Any, Optional

import gymnasium
import jax
import numpy as np
from gymnasium.envs.registration import EnvSpec

from octax_core.env.config import check_option_names
from octax_core.env.games import GameSpec
from octax_core.env.mix import MixEnv
from octax_gym.envs.choices import UnknownOptionError
from octax_gym.envs.vector import FRAMES_PER_SECOND, KEYWORDS, RENDER_MODES, OctaxVectorEnv
from octax_gym.step import action_check
from octax_gym.step import opponent as opponents

SINGLE_KEYWORDS = tuple(k for k in KEYWORDS if k != "autoreset_mode")  # a single env never autoresets
NO_BOUND = np.iinfo(np.int32).max  # an episode bound no episode reaches: the env's own bound, lifted
# What to use instead of the render modes Gymnasium's `make` would otherwise emulate with a wrapper
# (see `OctaxEnv.metadata`): the env refuses them with these words.
RENDER_MODE_HINTS = {
    "human": ("and not 'human', as this env opens no window: for a live view run `octax-gym play GAME` (in the "
              "browser); for a video, render_mode='rgb_array' with octax_gym.video.record or Gymnasium's "
              "RecordVideo; for a pygame window, gymnasium.wrappers.HumanRendering over render_mode='rgb_array' "
              "(pip install pygame)"),
    "rgb_array_list": "and for 'rgb_array_list', gymnasium.wrappers.RenderCollection over render_mode='rgb_array'",
}


def action_meanings(spec: GameSpec, seat: Optional[int] = None) -> list[str]:
    """What each action of a game does, in ale-py's `get_action_meanings` style: "NOOP" for
    action 0, then "KEY_<hex>" for the CHIP-8 key action i holds ("KEY_4"). A `GameSpec` maps
    actions to keys and says no more (a key's role is in its description and docs/games.md), so
    the names are the keys. `seat`: a two-player game's seat (`Seats.action_keys`)."""
    keys = spec.action_keys if seat is None else spec.seats.action_keys[seat]
    return ["NOOP"] + [f"KEY_{key:X}" for key in keys]


class OctaxEnv(gymnasium.Env):
    """One env; observation uint8 (frames_per_step, 32, 64), `Discrete(n)` actions (0 = no key).

    Takes the keywords of `OctaxVectorEnv` except `autoreset_mode` (a single env never
    autoresets: call `reset()` when an episode ends; steps after the end stand still). With
    backend "jax" or "torch" the observation is a JAX array or a torch tensor sharing its buffer;
    reward, terminated and truncated are Python scalars whatever the backend.

    Against an opponent (`opponent=`, `seat=`: `octax_gym.step.opponent`) the observation is the
    learner's, (frames_per_step + 1, H, W) with its player plane last; a function opponent takes
    one observation and returns one action; `info["action_mask"]` (int8 (n,), what
    `action_space.sample(mask=...)` takes; `action_masks()` gives it as bool) holds the actions
    open to the learner, and a closed one raises `IllegalMoveError`.

    Rendering: `render_mode="rgb_array"` or None; "human" (and "rgb_array_list") raise
    `UnknownOptionError` naming the alternatives (`RENDER_MODE_HINTS`).
    """

    _spec: Optional[EnvSpec] = None
    _metadata = {"render_modes": ["rgb_array"], "render_fps": FRAMES_PER_SECOND // 4}

    @property
    def metadata(self) -> dict:
        """{"render_modes": ["rgb_array"], "render_fps": 60 / frames_per_step}, per env (the fps
        follows its frames_per_step). A property, as Gymnasium's wrappers' metadata is, so that
        `gymnasium.make` hands `render_mode` to this env as given: were it a class dict without
        "human", `make` would swap in "rgb_array" and wrap the env in its pygame `HumanRendering`,
        which fails only at the first `reset` when pygame is missing; this env refuses "human" at
        once and says what to use instead (and so "rgb_array_list", which `make` would wrap in
        its `RenderCollection`)."""
        return self._metadata

    @metadata.setter
    def metadata(self, value: dict) -> None:
        self._metadata = value

    def __init__(self, game: Any, *, render_mode: Optional[str] = None, **options):
        check_option_names(options, SINGLE_KEYWORDS, type(self).__name__)
        if isinstance(render_mode, str) and render_mode in RENDER_MODE_HINTS:
            raise UnknownOptionError("render_mode", render_mode, RENDER_MODES, RENDER_MODE_HINTS[render_mode])
        if callable(options.get("opponent")):  # one observation -> one action, run as a batch of one
            options["opponent"] = opponents.single_env_function(options["opponent"])
        self._vector = OctaxVectorEnv(game, 1, autoreset_mode="disabled", render_mode=render_mode, **options)
        self.render_mode = render_mode
        self.backend = self._vector.backend
        self.game_spec = self._vector.game_spec
        self.observation_space = self._vector.single_observation_space
        self.action_space = self._vector.single_action_space
        self.metadata = {**self._metadata, "render_fps": self._vector.metadata["render_fps"]}

    @property
    def spec(self) -> Optional[EnvSpec]:
        """The `EnvSpec` `gymnasium.make` built this env from (None for an env built directly).

        Its `max_episode_steps` is where this env cuts episodes: the env's own bound where it keeps
        one. Behind `gymnasium.make` of a registered id it keeps none: `make` wraps it in
        Gymnasium's `TimeLimit`, whose spec shows that bound (the registered one, or the one given
        to `make`), and that wrapper alone counts the steps (see the setter).
        """
        spec = self._spec
        bound = np.asarray(self._vector.params.max_episode_steps)
        if spec is None or spec.max_episode_steps is not None or bound.ndim or int(bound) == NO_BOUND:
            return spec  # (a mix keeps one bound per game: no one number to show)
        return dataclasses.replace(spec, max_episode_steps=int(bound))

    @spec.setter
    def spec(self, spec: Optional[EnvSpec]) -> None:
        """Set by `gymnasium.make`, which then wraps this env in `TimeLimit` when the spec it
        makes from has a `max_episode_steps` (as every registered game's has) or `make` was given
        one, and not when `make` was given -1.

        The registered ids leave the env's own `max_episode_steps` keyword None in their kwargs
        (`octax_gym.envs.registration`): seeing that here, the env lifts its own bound, so that one
        truncation, `TimeLimit`'s, cuts episodes where `env.spec.max_episode_steps` says, also
        when `make(id, max_episode_steps=M)` asks for more than the game's default (and none with
        -1). A spec whose kwargs give the keyword a number keeps it as the env's own bound.
        """
        if spec is not None and "max_episode_steps" in spec.kwargs and spec.kwargs["max_episode_steps"] is None:
            params = self._vector.params
            if not np.ndim(params.max_episode_steps):  # one game (a mix keeps each game's bound)
                self._vector.params = dataclasses.replace(
                    params, max_episode_steps=jax.device_put(np.int32(NO_BOUND), self._vector.device))
        self._spec = spec

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None):
        super().reset(seed=seed)
        if options:
            raise UnknownOptionError("reset option(s)", sorted(options), (), "none (OctaxEnv.reset takes no options)")
        if seed is None and self._vector.state is None:
            seed = int(self.np_random.integers(0, 2**31 - 1))
        obs, info = self._vector.reset(seed=seed, options=None if self._vector.state is None
                                       else {"reset_mask": np.ones(1, bool)})
        return obs[0], self._unbatch(info)

    def step(self, action):
        value = action_check.to_int(action, self.action_space.n, self.game_spec.id)
        obs, reward, terminated, truncated, info = self._vector.step(np.array([value], np.int32))
        return obs[0], float(reward[0]), bool(terminated[0]), bool(truncated[0]), self._unbatch(info)

    def render(self) -> Optional[np.ndarray]:
        frames = self._vector.render()
        return None if frames is None else frames[0]

    def close(self):
        self._vector.close()
        super().close()

    @property
    def state(self):
        """The `octax_core.EnvState` (JAX arrays, batch axis of 1)."""
        return self._vector.state

    def action_masks(self) -> np.ndarray:
        """bool (n,): the actions open to the learner now (all of them in a one-player env or a
        simultaneous game), what sb3-contrib's MaskablePPO reads."""
        return np.asarray(self._vector.action_masks()[0], np.bool_)

    def get_action_meanings(self) -> list[str]:
        """ale-py's names of the actions: "NOOP", then the key each action holds ("KEY_4"); see
        `action_meanings`. Against an opponent, the learner seat's keys.

        Raises:
            ValueError: a mix of games, whose action i holds a different key in each game
                (`action_meanings(spec)` gives each game's).
        """
        if isinstance(self._vector.core_env, MixEnv):
            raise ValueError(f"{self._vector.game_name}: action i holds game g's i-th key, a different key in each "
                             "game; octax_gym.envs.env.action_meanings(octax_core.get_spec(game)) names one game's")
        view = self._vector.view
        return action_meanings(self.game_spec, None if view is None else view.seat)

    @staticmethod
    def _unbatch(info: dict) -> dict:
        return {name: (value[0].item() if hasattr(value[0], "item") and not getattr(value[0], "shape", ()) else value[0])
                for name, value in info.items() if not name.startswith("_")}

    def __repr__(self) -> str:
        return f"OctaxEnv({self.game_spec.id})"
