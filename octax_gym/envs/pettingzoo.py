"""PettingZoo envs of the two-player games: `parallel_env` (a `ParallelEnv`) and `env` (an `AECEnv`).

    from octax_gym import pettingzoo as octax_pz

    env = octax_pz.parallel_env("SpaceRacer")
    observations, infos = env.reset(seed=0)
    while env.agents:
        actions = {agent: env.action_space(agent).sample() for agent in env.agents}
        observations, rewards, terminations, truncations, infos = env.step(actions)

    env = octax_pz.env("SpaceRacer")                     # AEC: one agent at a time
    env.reset(seed=0)
    for agent in env.agent_iter():
        observation, reward, termination, truncation, info = env.last()
        env.step(None if termination or truncation else env.action_space(agent).sample())

Both run on `octax_gym.MultiAgentVectorEnv` with num_envs=1 (its DISABLED autoreset: the episode
stands still until `reset()`): the same compiled step, seeding and action checks as the batched
env. Importing this module imports pettingzoo (`pip install 'octax-gym[pettingzoo]'`).

Agents: "first_0" and "second_0" (PettingZoo's Atari names), seat 0 and seat 1 of the game
(`Seats.names`, e.g. the left and the right ship); both are removed together when the episode
ends (one machine, one episode).

Observations: uint8 Box (frames_per_step + 1, H, W): the step's screens, then the player plane, 0
everywhere for first_0 and `obs_scale` for second_0. For a turn-based game (`Seats.turn_fn`) an
agent's observation is PettingZoo classic's dict instead, {"observation": that Box, "action_mask":
int8 (n,)}, so that generic code (and PettingZoo's tests) sample legal actions; the mask opens
no-op alone to the agent whose turn it is not. Every agent's info holds `action_mask` too (int8,
every action open in a simultaneous game, what `action_space(agent).sample(mask=...)` takes), with
score (its seat's), lives (its seat's, see below), episode_step and current_player (the seat to
move, -1 in a simultaneous game).

Lives: a game's `GameSpec.lives_fn` counts player 1's lives (the one-player env's, and seat 0's
here), and `Seats` defines none per seat, so first_0's info has that count and second_0's -1,
the value that says "no count kept" everywhere (as both have in a game without `lives_fn`),
rather than player 1's count under player 2's name.

Actions: Discrete(n), 0 = no key. Rewards: each seat's own (the change of its score).

Turns: the AEC env's `agent_selection` is the game's seat to move in a turn-based game (the same
agent again while its turn lasts: CHIP-8 games often take several steps a move), and steps the
machine once per action, the other seat playing no-op. In a simultaneous game the AEC env
collects first_0's action, then second_0's, and steps the machine once with both (as PettingZoo's
`parallel_to_aec`); rewards arrive with the second action.

Errors (all before the machine steps): an action out of 0..n-1 raises `InvalidActionError`, one
the mover's legal mask closes `IllegalMoveError`, an unknown agent or a missing action (a live
agent of a simultaneous game) ValueError. In the parallel env of a turn-based game the actions of
the agent whose turn it is not are ignored (played as no-op) by default, as PettingZoo's own
turn-based parallel envs (`turn_based_aec_to_parallel`) do and its `parallel_seed_test` needs;
`off_turn="raise"` makes any non-zero one raise `IllegalMoveError`, as `MultiAgentVectorEnv` does.

`reset(options=...)` takes no options; any given are ignored (PettingZoo's API test passes some).
"""

from __future__ import annotations

import functools
from typing import Any, Optional

import gymnasium
import numpy as np
from gymnasium import spaces
from pettingzoo import AECEnv, ParallelEnv

from octax_gym.envs.choices import check_choice
from octax_gym.envs.multi_vector import MultiAgentVectorEnv
from octax_gym.step.action_check import to_int
from octax_gym.step.opponent import NO_LIVES  # the one definition, shared with the one-seat view

FIXED_KEYWORDS = ("autoreset_mode", "backend")  # PettingZoo steps one episode of numpy arrays
OFF_TURN = ("ignore", "raise")


class OctaxParallelEnv(ParallelEnv):
    """A two-player game as a PettingZoo `ParallelEnv`; see the module docstring.

    Args:
        game: a two-player game's id (`octax_core.list_games(players=2)`), its Gymnasium id, or a
            `GameSpec` with seats.
        render_mode: None or "rgb_array" (`render()` returns the screen, as `OctaxEnv`).
        off_turn: "ignore" (the default) or "raise": what a turn-based game's parallel step does
            with a non-zero action of the agent whose turn it is not.
        **options: `MultiAgentVectorEnv`'s keywords but autoreset_mode and backend: device,
            render_scale, palette, rom, and the env options (frames_per_step, obs_scale,
            max_episode_steps, repeat_action_probability, ...).
    """

    metadata = {"render_modes": ["rgb_array"], "name": "octax", "is_parallelizable": True, "render_fps": 15}

    def __init__(self, game: Any, *, render_mode: Optional[str] = None, off_turn: str = "ignore", **options):
        fixed = sorted(set(options) & set(FIXED_KEYWORDS))
        if fixed:
            raise TypeError(f"the PettingZoo envs fix {fixed} (one episode at a time, numpy arrays); drop them, "
                            f"or use octax_gym.MultiAgentVectorEnv")
        self.off_turn = check_choice("off_turn", off_turn, OFF_TURN)
        self.vector_env = MultiAgentVectorEnv(game, 1, autoreset_mode="disabled", backend="numpy",
                                              render_mode=render_mode, **options)
        self.render_mode = render_mode
        self.game_spec = self.vector_env.game_spec
        self.turn_based = self.vector_env.turn_based
        self.num_actions = self.vector_env.num_actions
        self.possible_agents = list(self.vector_env.agents)
        self.agents: list[str] = []
        self.metadata = {**type(self).metadata, "name": f"octax_{self.game_spec.id}_v{self.game_spec.version}",
                         "render_fps": self.vector_env.metadata["render_fps"]}
        box = self.vector_env.agent_observation_space
        mask = spaces.Box(0, 1, (self.num_actions,), np.int8)
        self.observation_spaces = {agent: spaces.Dict({"observation": box, "action_mask": mask}) if self.turn_based
                                   else spaces.Box(box.low, box.high, box.shape, box.dtype)
                                   for agent in self.possible_agents}
        self.action_spaces = {agent: spaces.Discrete(self.num_actions) for agent in self.possible_agents}
        self._info: Optional[dict] = None

    def observation_space(self, agent: str) -> spaces.Space:
        return self.observation_spaces[self._check_agent(agent)]

    def action_space(self, agent: str) -> spaces.Space:
        return self.action_spaces[self._check_agent(agent)]

    def reset(self, seed: Optional[int] = None, options: Optional[dict] = None):
        """A new episode; `seed` as `MultiAgentVectorEnv.reset` (an int, or None to go on from the
        last seed's key chain). Options are ignored."""
        obs, info = self.vector_env.reset(seed=seed)
        self.agents = self.possible_agents[:]
        return self._observations(obs, info, self.agents), self._infos(info, self.agents)

    def step(self, actions: dict[str, Any]):
        """One machine step with every live agent's action (see the module docstring for turns)."""
        if not self.agents:
            raise gymnasium.error.ResetNeeded("the episode has ended (no agents left): call reset()")
        unknown = sorted(set(actions) - set(self.agents), key=str)
        if unknown:
            raise ValueError(f"{self.game_spec.id}: actions for unknown agent(s) {unknown}; agents: {self.agents}")
        mover = int(self._info["current_player"][0])
        row = np.zeros((1, len(self.possible_agents)), np.int64)
        for seat, agent in enumerate(self.possible_agents):
            if agent not in actions:
                if mover < 0 or seat == mover:
                    raise ValueError(f"{self.game_spec.id}: no action for {agent}; give one for each of {self.agents}")
                continue
            row[0, seat] = to_int(actions[agent], self.num_actions, self.game_spec.id, agent)
        if self.turn_based and self.off_turn == "ignore" and mover >= 0:
            row[0, 1 - mover] = 0  # the other seat's action, ignored (PettingZoo's turn-based parallel convention)
        obs, reward, terminated, truncated, info = self.vector_env.step(row)
        agents = self.agents  # those live before the step get its outputs; none is left after an end
        if terminated[0] or truncated[0]:
            self.agents = []
        observations, infos = self._observations(obs, info, agents), self._infos(info, agents)
        return (observations, {agent: float(reward[0, seat]) for seat, agent in enumerate(agents)},
                dict.fromkeys(agents, bool(terminated[0])), dict.fromkeys(agents, bool(truncated[0])), infos)

    def render(self) -> Optional[np.ndarray]:
        frames = self.vector_env.render()
        return None if frames is None else frames[0]

    def close(self):
        self.vector_env.close()

    def state(self) -> np.ndarray:
        """The global state: the step's screens (frames_per_step, H, W), what both seats see."""
        if self._info is None:
            raise gymnasium.error.ResetNeeded("call reset() before state()")
        return np.asarray(self.vector_env._obs)[0, 0, :-1]

    @functools.cached_property
    def state_space(self) -> spaces.Box:
        box = self.vector_env.agent_observation_space
        return spaces.Box(0, box.high.max(), (box.shape[0] - 1, *box.shape[1:]), np.uint8)

    # --- helpers ----------------------------------------------------------------------------

    def _observations(self, obs: np.ndarray, info: dict, agents: list[str]) -> dict[str, Any]:
        self._info = info
        seats = [(self.possible_agents.index(agent), agent) for agent in agents]
        if not self.turn_based:
            return {agent: obs[0, seat] for seat, agent in seats}
        masks = info["legal_action_mask"][0].astype(np.int8)
        return {agent: {"observation": obs[0, seat], "action_mask": masks[seat]} for seat, agent in seats}

    def _infos(self, info: dict, agents: list[str]) -> dict[str, dict]:
        masks = info["legal_action_mask"][0].astype(np.int8)
        lives = (int(info["lives"][0]), NO_LIVES)  # per seat: `lives_fn` is player 1's (module docstring)
        shared = {"episode_step": int(info["episode_step"][0]), "current_player": int(info["current_player"][0])}
        return {agent: {"score": float(info["score"][0, seat]), "lives": lives[seat], **shared,
                        "action_mask": masks[seat]}
                for seat, agent in ((self.possible_agents.index(agent), agent) for agent in agents)}

    def _check_agent(self, agent: str) -> str:
        if agent not in self.possible_agents:
            raise ValueError(f"{self.game_spec.id}: unknown agent {agent!r}; agents: {self.possible_agents}")
        return agent

    def __repr__(self) -> str:
        return f"OctaxParallelEnv({self.game_spec.id})"


class OctaxAECEnv(AECEnv):
    """A two-player game as a PettingZoo `AECEnv` (one agent acts at a time); see the module
    docstring. Takes `OctaxParallelEnv`'s arguments (but `off_turn`: only the mover acts here) and
    steps the machine through it."""

    metadata = OctaxParallelEnv.metadata

    def __init__(self, game: Any, *, render_mode: Optional[str] = None, **options):
        if "off_turn" in options:
            raise TypeError("the AEC env takes no off_turn: only the agent to move acts")
        self.parallel = OctaxParallelEnv(game, render_mode=render_mode, off_turn="raise", **options)
        self.render_mode = render_mode
        self.game_spec = self.parallel.game_spec
        self.turn_based = self.parallel.turn_based
        self.metadata = self.parallel.metadata
        self.possible_agents = self.parallel.possible_agents[:]
        self.observation_spaces = self.parallel.observation_spaces
        self.action_spaces = self.parallel.action_spaces
        self.agents: list[str] = []
        self._observations: dict[str, Any] = {}
        self._pending: dict[str, Any] = {}

    def observation_space(self, agent: str) -> spaces.Space:
        return self.parallel.observation_space(agent)

    def action_space(self, agent: str) -> spaces.Space:
        return self.parallel.action_space(agent)

    def reset(self, seed: Optional[int] = None, options: Optional[dict] = None):
        self._observations, self.infos = self.parallel.reset(seed=seed, options=options)
        self.agents = self.parallel.agents[:]
        self.rewards = dict.fromkeys(self.agents, 0.0)
        self._cumulative_rewards = dict.fromkeys(self.agents, 0.0)
        self.terminations = dict.fromkeys(self.agents, False)
        self.truncations = dict.fromkeys(self.agents, False)
        self._pending = {}
        self._skip_agent_selection = None
        self.agent_selection = self._to_move(self.agents[0])

    def observe(self, agent: str) -> Any:
        return self._observations[self.parallel._check_agent(agent)]

    def step(self, action: Any) -> None:
        agent = self.agent_selection
        if self.terminations[agent] or self.truncations[agent]:
            self._was_dead_step(action)
            return
        if action is None:
            raise ValueError(f"{self.game_spec.id}: {agent} is live: its action is an int in "
                             f"0..{self.parallel.num_actions - 1}, not None")
        self._cumulative_rewards[agent] = 0.0
        if not self.turn_based and agent != self.agents[-1]:
            self._pending[agent] = action  # the machine steps once both have acted
            self._clear_rewards()
            self.agent_selection = self.agents[self.agents.index(agent) + 1]
            self._accumulate_rewards()
            return
        actions, self._pending = {**self._pending, agent: action}, {}
        observations, rewards, terminations, truncations, infos = self.parallel.step(actions)
        self._observations = observations
        self.rewards, self.terminations, self.truncations = rewards, terminations, truncations
        self.infos = infos
        self._accumulate_rewards()
        if self.parallel.agents:
            self.agent_selection = self._to_move(self.agents[0])
        else:
            self._deads_step_first()

    def render(self) -> Optional[np.ndarray]:
        return self.parallel.render()

    def close(self):
        self.parallel.close()

    def state(self) -> np.ndarray:
        return self.parallel.state()

    @property
    def state_space(self) -> spaces.Box:
        return self.parallel.state_space

    # --- helpers ----------------------------------------------------------------------------

    def _to_move(self, otherwise: str) -> str:
        """The agent to move: the game's in a turn-based game, `otherwise` in a simultaneous one."""
        mover = int(self.parallel._info["current_player"][0])
        return self.possible_agents[mover] if mover >= 0 else otherwise

    def __repr__(self) -> str:
        return f"OctaxAECEnv({self.game_spec.id})"


def parallel_env(game: Any, *, render_mode: Optional[str] = None, **options) -> OctaxParallelEnv:
    """The PettingZoo `ParallelEnv` of a two-player game (`OctaxParallelEnv`)."""
    return OctaxParallelEnv(game, render_mode=render_mode, **options)


def env(game: Any, *, render_mode: Optional[str] = None, **options) -> OctaxAECEnv:
    """The PettingZoo `AECEnv` of a two-player game (`OctaxAECEnv`)."""
    return OctaxAECEnv(game, render_mode=render_mode, **options)


raw_env = env  # PettingZoo's name for an env without wrappers
