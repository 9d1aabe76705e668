"""`OctaxVectorEnv`: a `gymnasium.vector.VectorEnv` over the batched JAX core.

    import gymnasium as gym, octax_gym
    gym.register_envs(octax_gym)
    envs = gym.make_vec("octax/Pong-v0", num_envs=512)          # or OctaxVectorEnv("Pong", 512)
    obs, info = envs.reset(seed=0)
    obs, reward, terminated, truncated, info = envs.step(envs.action_space.sample())

A step is one jitted call (key split, batched step, autoreset) with no host sync inside; the
outputs reach numpy, JAX or torch without a copy (`backend=`). See docs/gymnasium.md.

With `opponent=` (and `seat=`) a two-player game is one seat against a fixed opponent, still a
one-player vector env to its caller (`octax_gym.step.opponent`, docs/pettingzoo.md); both seats at
once are `octax_gym.MultiAgentVectorEnv`, a subclass.
"""

from __future__ import annotations

import inspect
from typing import Any, Optional, Union

import gymnasium
import jax
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode

from octax_core.emulator.state import screen_values, shown
from octax_core.env.config import check_option_names
from octax_core.validate import check_int
from octax_gym.envs import render
from octax_gym.envs.choices import UnknownOptionError, check_choice, check_names
from octax_gym.envs.game_names import resolve_spec
from octax_gym.step import action_check, backends, compiled_step, opponent as opponents, sharding
from octax_gym.step.compiled_step import GYM_ENV_OPTIONS, build, keys_from_seeds, seeds_for

FRAMES_PER_SECOND = 60  # the timer rate, on all three platforms; a step lasts frames_per_step frames
RENDER_MODES = (None, "rgb_array")
RESET_OPTIONS = ("reset_mask",)


def check_autoreset_mode(mode) -> AutoresetMode:
    """An `AutoresetMode`, or its name in any case, with or without underscores ("same_step").

    Raises:
        UnknownOptionError: anything else; the message lists the names.
    """
    if isinstance(mode, AutoresetMode):
        return mode
    for member in AutoresetMode:
        if isinstance(mode, str) and mode.lower().replace("_", "") in (member.value.lower(), member.name.lower().replace("_", "")):
            return member
    members = ", ".join(f"AutoresetMode.{member.name}" for member in AutoresetMode)
    raise UnknownOptionError("autoreset_mode", mode, [member.name.lower() for member in AutoresetMode],
                             f"or an AutoresetMode ({members})")


class OctaxVectorEnv(gymnasium.vector.VectorEnv):
    """`num_envs` copies of one game (CHIP-8, SUPER-CHIP or XO-CHIP), stepped together by one
    jitted JAX call.

    Observation: uint8 (num_envs, frames_per_step, H, W), the screen after each 60 Hz frame of the
    step, 32 x 64 on CHIP-8 and 64 x 128 on SUPER-CHIP and XO-CHIP; lit pixels `obs_scale` (1 or
    255), XO-CHIP's by plane (1, 2, 3, or 85, 170, 255; docs/env.md). Action: int per env in 0..n-1, 0 = no key, i =
    the game's i-th key held for the whole step. Reward: change of the game's score, float32.
    `info`: score, lives (-1 where the game keeps none), episode_step, each with its `_` mask.

    Autoreset (`autoreset_mode`, Gymnasium's `AutoresetMode`):
      NEXT_STEP (default): the step after an episode ends resets that env; its action is ignored,
        reward 0, flags False.
      SAME_STEP: the ending step returns the new episode's first observation; the last one is in
        `info["final_obs"]` and its info in `info["final_info"]`, batched, rows marked by
        `info["_final_obs"]` / `info["_final_info"]`.
      DISABLED: ended envs stand still (same observation, reward 0, same flags) until you call
        `reset(options={"reset_mask": mask})`.

    Args:
        game: a registered game id ("Pong"; see `octax_core.list_games()`), its Gymnasium id
            ("octax/Pong-v0"), either in any case (`octax_gym.envs.game_names`), or a `GameSpec`.
        num_envs: number of envs in the batch.
        autoreset_mode: see above.
        backend: "numpy" (default), "jax" or "torch"; arrays are handed over without copies.
        device: where the env runs and its arrays live: None (JAX's default), "cpu", "cuda",
            "cuda:1", a jax.Device or a torch.device.
        devices: the batch sharded over several devices, of this process or of every process of
            a `jax.distributed` run: "all", a list of devices, or a Mesh with an axis "envs"
            (`octax_gym.step.sharding`). `num_envs` is then the global batch; the env's `num_envs` and
            arrays are this process's lanes, `global_env_ids` their global indices. docs/scale.md.
        render_mode: None or "rgb_array" (`render()` returns a tuple of num_envs frames).
        render_scale: pixel size of a rendered frame (default 8: 512 x 256).
        palette: a name from `octax_gym.envs.render.PALETTES`, an (off, on) pair of RGB triples or
            four (off, plane 1, plane 2, both: XO-CHIP's colours); None (the default) takes the
            game's own (`GameSpec.palette`), else "white".
        rom: an explicit ROM path (its SHA-1 must match the game's).
        opponent: for a two-player game (`octax_core.list_games(players=2)`), the fixed player of
            the other seat: "random", "noop", "scripted" (the game's bot) or a function of a batch
            of the opponent's observations -> its num_envs actions (`octax_gym.step.opponent`). The
            env is then the learner's seat alone: observation (frames_per_step + 1, H, W), the
            last plane the player plane; its own reward; `info["action_mask"]` and
            `info["current_player"]`; a closed action raises `IllegalMoveError`. None (the
            default): a one-player env; a game that is not one (`GameSpec.solo` False) then
            raises `OpponentRequiredError`.
        seat: the learner's seat against `opponent`: 0 (the default, first_0) or 1 (second_0).
        games: a mix of games in one batch (`octax_core.make_mix`): a list of game names (one
            platform), or a named mix ("octax16"), in place of `game` ("octax/Mix-v0" takes it).
            Each env plays one of them, drawn from `weights` at every reset; the action space is
            the largest game's (an action past an env's game's last holds no key), and `info`
            adds `game` (the index into `games`) and `action_mask` (the actions its game takes).
            `game` may also be given as such a list or name.
        weights: how often each game of the mix is drawn (normalised); None: uniform.
        **env_options: the core env's options (`octax_core.env.config`; None or absent = the
            game's default), all but `autoreset`: frames_per_step, instructions_per_frame,
            obs_scale, freeze_timers and noop_max, fixed at construction (`EnvConfig`), and
            max_episode_steps and repeat_action_probability (`EnvParams`).
    """

    metadata = {"render_modes": ["rgb_array"], "autoreset_mode": AutoresetMode.NEXT_STEP,
                "render_fps": FRAMES_PER_SECOND // 4}

    def __init__(self, game: Any, num_envs: int = 1, *,
                 autoreset_mode: Union[AutoresetMode, str] = AutoresetMode.NEXT_STEP,
                 backend: str = "numpy", device: Any = None, render_mode: Optional[str] = None,
                 render_scale: int = render.DEFAULT_RENDER_SCALE, palette: Optional[render.PaletteArg] = None,
                 rom=None, opponent: Any = None, seat: int = 0, games: Any = None, weights: Any = None,
                 devices: Any = None, **env_options):
        check_option_names(env_options, KEYWORDS, type(self).__name__)
        if games is not None:  # "octax/Mix-v0" with games=[...]
            game = games if isinstance(games, str) else tuple(games)
        if weights is not None and not compiled_step.is_mix(game):
            raise ValueError("weights= is for a mix of games (games=[...]); one game has no weights")
        self._weights = weights
        self._setup(game, num_envs, autoreset_mode, backend, device, render_mode, render_scale, palette, rom,
                    env_options, opponent=opponent, seat=seat, devices=devices)

    def _setup(self, game, num_envs, autoreset_mode, backend, device, render_mode, render_scale, palette, rom,
               env_options, *, players: int = 1, opponent: Any = None, seat: int = 0, devices: Any = None):
        """The construction `MultiAgentVectorEnv` shares: arguments checked, compiled step built."""
        self.num_envs = self.global_num_envs = check_int("num_envs", num_envs)
        self.autoreset_mode = check_autoreset_mode(autoreset_mode)
        self.backend = backends.check_backend(backend)
        self._shards = None
        if devices is None:
            self.device = backends.resolve_device(device)
        else:
            if device is not None:
                raise ValueError("give device= (one device) or devices= (the batch sharded over several), not both")
            if opponent is not None or players != 1:
                raise ValueError("devices= shards one-player envs; a two-player env or an opponent= runs on one device")
            self._shards = sharding.Shards(devices, self.num_envs)
            self.device, self.num_envs = self._shards.device, self._shards.num_local
        self.global_env_ids = np.arange(self.num_envs) if self._shards is None else self._shards.global_env_ids
        self.render_mode = check_choice("render_mode", render_mode, RENDER_MODES)
        self.render_scale = render.check_render_scale(render_scale)
        if palette is not None:
            self.palette = render.resolve_palette(palette)  # a bad one raises before the build
        view = self._opponent = None
        mix = players == 1 and compiled_step.is_mix(game)
        if mix:
            if opponent is not None or rom is not None:
                raise ValueError("a mix of games takes no opponent= or rom= (each game's ROM comes from the store)")
            self._compiled, params = compiled_step.build_mix(game, getattr(self, "_weights", None), env_options)
        elif players == 1:
            spec = resolve_spec(game)
            view, self._opponent = opponents.resolve(opponent, seat, spec)
            if view is not None:
                players, game = 2, spec
        self.view = view
        if not mix:
            self._compiled, params = build(game, rom, env_options, players=players, view=view)
        self.core_env = self._compiled.env
        self.game_spec = self.core_env.spec  # a mix's first game's (its palette is the mix's)
        self.game_name = f"mix({', '.join(self.core_env.games)})" if mix else self.game_spec.id
        self.agents = getattr(self.core_env, "agents", None)  # the seats' names in a two-player env
        if palette is None:
            self.palette = render.resolve_palette(self.game_spec.palette or render.DEFAULT_PALETTE)
        self.params = jax.device_put(params, self.device) if self._shards is None else self._shards.replicate(params)
        self._step_fn, self._reset_fn = self._compiled.step[self.autoreset_mode], self._compiled.reset
        if self._shards is not None:
            self._step_fn, self._reset_fn = (
                self._shards.partitioned(fn, self._compiled.compiler_options)
                for fn in (self._compiled.step_fns[self.autoreset_mode], self._compiled.reset_fn))
        self._action_check = action_check.DeferredCheck(
            self.game_name, self.core_env.num_actions, self.device if self._shards is None else self._shards.replicated,
            self.agents)

        config = self.core_env.config
        self.metadata = {**type(self).metadata, "autoreset_mode": self.autoreset_mode,
                         "render_fps": FRAMES_PER_SECOND / config.frames_per_step}
        self.single_observation_space = spaces.Box(0, self.core_env.observation_high, self.core_env.observation_shape,
                                                   np.uint8)
        self.single_action_space = spaces.Discrete(self.core_env.num_actions)
        self.observation_space = gymnasium.vector.utils.batch_space(self.single_observation_space, self.num_envs)
        self.action_space = gymnasium.vector.utils.batch_space(self.single_action_space, self.num_envs)
        self._keys = self._state = self._obs = self._info = None

    # --- Gymnasium API ----------------------------------------------------------------------

    def reset(self, *, seed: Optional[Union[int, list[int]]] = None, options: Optional[dict] = None):
        """Resets every env, or with `options={"reset_mask": m}` (bool numpy array (num_envs,))
        only the rows where m is True. An int seed s seeds env i with s + i (with `devices=`, global
        env i: `global_env_ids[j]` for this process's row j; a list of seeds is the global batch's)."""
        seeds = None if seed is None else seeds_for(seed, self.global_num_envs)  # checks the seed first
        self._action_check.poll()  # earlier steps' device actions whose check has finished
        super().reset(seed=int(seed) if isinstance(seed, (int, np.integer)) else None)
        options = dict(options or {})
        mask = options.pop("reset_mask", None)
        check_names("reset option(s)", options, RESET_OPTIONS)
        if mask is not None:
            mask = self._check_mask(mask)
        if self._state is None or seeds is not None:
            if seeds is None:  # the first reset without a seed: draw one
                seeds = seeds_for(int(self.np_random.integers(0, 2**31 - self.global_num_envs)), self.global_num_envs)
            if self._shards is None:
                keys = jax.device_put(keys_from_seeds(seeds), self.device)
            else:
                keys = self._shards.keys([seeds[i] for i in self.global_env_ids])
            if self._keys is None or mask is None:
                self._keys = keys
            else:
                self._keys = compiled_step.select_keys(self._batch(mask), keys, self._keys)
        if self._state is None or mask is None:
            self._keys, self._obs, self._state, info = self._reset_fn(self._keys, None, None, None, self.params)
        else:
            self._keys, self._obs, self._state, info = self._reset_fn(
                self._keys, self._state, self._obs, self._batch(mask), self.params)
        self._info = info = self._local(info)
        return backends.to_backend(self._local(self._obs), self.backend), backends.to_backend(info, self.backend)

    def step(self, actions):
        """Steps every env with its action; one jitted call, no host sync inside it.

        Actions are ints in 0..n-1, one per env: a numpy array or list (checked here: a bad one
        raises before anything runs), or a JAX array or torch tensor (never read here, so the
        step need not wait for whatever computes them: shape and dtype are checked at once,
        the range inside the step, and `InvalidActionError` surfaces at a later call; see
        `octax_gym.step.action_check`).
        """
        if self._state is None:
            raise gymnasium.error.ResetNeeded("call reset() before step()")
        given = self._actions_to_device(actions)
        self._action_check.poll()
        extra = () if self._opponent is None else (self._opponent_actions(),)
        self._keys, self._obs, self._state, reward, terminated, truncated, info, report = self._step_fn(
            self._keys, self._state, given.actions, self._action_check.report, self.params, *extra)
        self._action_check.record(report, given.unchecked, given.given)
        obs, reward, terminated, truncated, info = self._local((self._obs, reward, terminated, truncated, info))
        self._info = info
        out = backends.to_backend((obs, reward, terminated, truncated, info), self.backend)
        if self.backend == "numpy":  # the outputs were just read back, so the report is ready too
            self._action_check.poll(wait=True)
        return out

    def render(self) -> Optional[tuple[np.ndarray, ...]]:
        """One RGB frame per env, the current screens: H = 32 * render_scale, W = 64 * render_scale
        on CHIP-8, twice that on SUPER-CHIP and XO-CHIP (XO-CHIP in the palette's four colours)."""
        if self.render_mode is None:
            gymnasium.logger.warn("render() needs render_mode='rgb_array' at construction; returning None")
            return None
        if self._state is None:
            raise gymnasium.error.ResetNeeded("call reset() before render()")
        pixels = screen_values(np.asarray(shown(self._local(self._state).machine)), self.core_env.machine.platform)
        return tuple(render.to_rgb(p, self.render_scale, self.palette) for p in pixels)

    def close_extras(self, **kwargs):
        self._keys = self._state = self._obs = self._info = None
        self._action_check.poll(wait=True)  # the last steps' device actions, checked at the latest here

    # --- helpers ----------------------------------------------------------------------------

    def _batch(self, rows: np.ndarray) -> jax.Array:
        """This process's rows of a batched host array where the step reads it: on the device, or
        with `devices=` into the global batch."""
        return jax.device_put(rows, self.device) if self._shards is None else self._shards.to_global(rows)

    def _local(self, tree):
        """The step's outputs as this process's rows (with `devices=`; as they are otherwise)."""
        return tree if self._shards is None else self._shards.to_local(tree)

    def _actions_to_device(self, actions) -> action_check.DeviceActions:
        """The step's actions checked (`action_check.to_device`: (num_envs,), or (num_envs, 2) in a
        `MultiAgentVectorEnv`) and on the device; host ones against a turn-based game's legal mask
        too. With `devices=` they are read to the host, checked there, and placed into the global batch."""
        if self._shards is not None:
            host = action_check.check_batch(action_check.to_host(actions), self.num_envs,
                                            self.single_action_space.n, self.game_name)
            return action_check.DeviceActions(self._shards.to_global(host.astype(np.int32)), False)
        turn_based = self.agents is not None and self.core_env.turn_based  # agents: a two-player core env
        return action_check.to_device(actions, self.num_envs, self.core_env.num_actions, self.device, self.game_name,
                                      self.agents if self.view is None else None, self._turns if turn_based else None)

    def _turns(self) -> action_check.Turns:
        """A turn-based game's state after the last step, on the host: the legal mask of both seats
        (`MultiAgentVectorEnv`) or of the learner's against an opponent."""
        info = self._info
        legal = info["legal_action_mask"] if self.view is None else info["action_mask"]
        return action_check.Turns(np.asarray(legal), np.asarray(info["current_player"]), np.asarray(self._state.done),
                                  self.agents, None if self.view is None else self.view.seat)

    def _opponent_actions(self) -> jax.Array:
        """A function opponent's actions for this step, from its own observation (the learner's
        with the opponent's player plane), in the env's backend type; checked on the host."""
        plane = self.view.other * self.core_env.config.obs_scale
        theirs = backends.to_backend(self._obs.at[:, -1].set(np.uint8(plane)), self.backend)
        actions = action_check.check_batch(action_check.to_host(self._opponent(theirs)), self.num_envs,
                                           self.single_action_space.n, self.game_spec.id, "from the opponent")
        return jax.device_put(actions.astype(np.int32), self.device)

    def action_masks(self) -> np.ndarray:
        """bool (num_envs, num_actions): the actions open to the learner now (against an opponent),
        as sb3-contrib's MaskablePPO reads them; every action in a one-player env."""
        if self._info is None:
            raise gymnasium.error.ResetNeeded("call reset() before action_masks()")
        if self.view is None:
            return np.ones((self.num_envs, self.single_action_space.n), np.bool_)
        return np.asarray(self._info["action_mask"], np.bool_)  # info's is int8, for Gymnasium's sample(mask=)

    @property
    def game(self) -> str:
        return self.game_name

    @property
    def state(self):
        """The batched `octax_core.EnvState` (JAX arrays), for inspection and tools."""
        return self._state

    def _check_mask(self, mask) -> np.ndarray:
        if not isinstance(mask, np.ndarray) or mask.dtype != np.bool_ or mask.shape != (self.num_envs,):
            raise ValueError(f"options['reset_mask'] must be a numpy bool array of shape ({self.num_envs},), "
                             f"got {type(mask).__name__} {getattr(mask, 'dtype', '')} {getattr(mask, 'shape', '')}")
        if not mask.any():
            raise ValueError("options['reset_mask'] must have at least one True row")
        if self._state is None and not mask.all():
            raise ValueError("the first reset() resets every env: a reset_mask must be all True or absent")
        return mask

    def __repr__(self) -> str:
        against = "" if self.view is None else f", seat={self.view.seat}, opponent={self.view.opponent!r}"
        return f"{type(self).__name__}({self.game_name}, num_envs={self.num_envs}, backend={self.backend!r}{against})"


# Every keyword the vector env takes: its own (the keyword-only arguments above) and the core's
# env options (`octax_core.env.config`, autoreset aside: `autoreset_mode` replaces it).
KEYWORDS = tuple(name for name, parameter in inspect.signature(OctaxVectorEnv.__init__).parameters.items()
                 if parameter.kind == inspect.Parameter.KEYWORD_ONLY) + GYM_ENV_OPTIONS
