"""`OctaxEnv`: one game (CHIP-8, SUPER-CHIP or XO-CHIP) as a `gymnasium.Env`, behind `gymnasium.make`.

It runs the same compiled env step as `OctaxVectorEnv` with a batch of one, so a single env
seeded s and row i of a vector env seeded s - i play the same game step for step. For many envs
use `gymnasium.make_vec`: one batched call is far faster than many single envs.

A two-player game is one seat against a fixed opponent with `opponent=` (and `seat=`):
`gymnasium.make("octax/SpaceRacer-v0", opponent="scripted")`; see `octax_gym.opponent`.
"""

from __future__ import annotations

from typing import Any, Optional

import gymnasium
import numpy as np

from octax_core.env.config import check_option_names
from octax_gym import action_check
from octax_gym import opponent as opponents
from octax_gym.choices import UnknownOptionError
from octax_gym.vector import FRAMES_PER_SECOND, KEYWORDS, OctaxVectorEnv

SINGLE_KEYWORDS = tuple(k for k in KEYWORDS if k != "autoreset_mode")  # a single env never autoresets


class OctaxEnv(gymnasium.Env):
    """One env; observation uint8 (frames_per_step, 32, 64), `Discrete(n)` actions (0 = no key).

    Takes the keywords of `OctaxVectorEnv` except `autoreset_mode` (a single env never
    autoresets: call `reset()` when an episode ends; steps after the end stand still). With
    backend "jax" or "torch" the observation is a JAX array or a torch tensor sharing its buffer;
    reward, terminated and truncated are Python scalars whatever the backend.

    Against an opponent (`opponent=`, `seat=`: `octax_gym.opponent`) the observation is the
    learner's, (frames_per_step + 1, H, W) with its player plane last; a function opponent takes
    one observation and returns one action; `info["action_mask"]` (bool (n,), also
    `action_masks()`) holds the actions open to the learner, and a closed one raises
    `IllegalMoveError`.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": FRAMES_PER_SECOND // 4}

    def __init__(self, game: Any, *, render_mode: Optional[str] = None, **options):
        check_option_names(options, SINGLE_KEYWORDS, type(self).__name__)
        if callable(options.get("opponent")):  # one observation -> one action, run as a batch of one
            options["opponent"] = opponents.single_env_function(options["opponent"])
        self._vector = OctaxVectorEnv(game, 1, autoreset_mode="disabled", render_mode=render_mode, **options)
        self.render_mode = render_mode
        self.backend = self._vector.backend
        self.game_spec = self._vector.game_spec
        self.observation_space = self._vector.single_observation_space
        self.action_space = self._vector.single_action_space
        self.metadata = {**type(self).metadata, "render_fps": self._vector.metadata["render_fps"]}

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
        return self._vector.action_masks()[0]

    @staticmethod
    def _unbatch(info: dict) -> dict:
        return {name: (value[0].item() if hasattr(value[0], "item") and not getattr(value[0], "shape", ()) else value[0])
                for name, value in info.items() if not name.startswith("_")}

    def __repr__(self) -> str:
        return f"OctaxEnv({self.game_spec.id})"
