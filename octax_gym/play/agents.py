"""Trained agents for `octax-gym play --agent PATH`: a function of one seat's observation -> action.

Two formats:

* `*.msgpack`: the params `octax-gym train` saves (`OUT/agents/<game>-seed<s>.msgpack`:
  `flax.serialization.to_bytes` of `octax_gym.train.networks`' `ActorCritic` or `QNetwork`; the
  older examples' files too), run by `octax_gym.jax_policy` with the package's network; it plays
  greedily (the largest logit or Q-value among the game's actions). Needs flax (the `train` extra).
* `*.zip`: a Stable-Baselines3 model (`model.save(...)`: PPO, A2C or DQN over
  `octax_gym.integrations.sb3.OctaxCNNExtractor`), played with `policy.predict(obs, deterministic=True)` as the
  model's own `predict`. SB3's loader unpickles the zip, which runs any code stored in it, so the
  policy is rebuilt from the zip's JSON and tensors alone (`octax_gym.play.sb3_zip`); other zips
  are refused unless `trust=True` (`--trust-agent`) hands them to SB3's loader. Needs the `sb3` extra.

An agent trained on one-player observations (F frames) and set in a two-player seat is given the
F screens without the player plane; one trained with the plane (self-play) gets it.
"""

from __future__ import annotations

import zipfile
from pathlib import Path
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np

from octax_gym import jax_policy

Agent = Callable[[np.ndarray], int]


def load_agent(path, num_actions: int, *, trust: bool = False, spec=None) -> Agent:
    """The agent saved at `path` (.msgpack or .zip) for a game of `num_actions` actions.

    Args:
        trust: load an SB3 zip with SB3's own loader, which unpickles it (runs code stored in the
            file): only for files the user vouches for. Without it nothing in the file runs.
        spec: the game's `GameSpec`; an agent trained with mirrored seats (`--mirror`, its file
            says so) needs it: in seat 1 it is shown the mirror image and its action is mapped
            back (`_as_trained`), as in the mirrored env it trained in.

    Raises:
        FileNotFoundError: no such file. ValueError: an unknown format, params that do not fit the
        game, or (`sb3_zip.AgentFileError`) a zip that cannot be read without running code from
        it. ImportError: flax or stable-baselines3 missing.
    """
    path = Path(path).expanduser()
    if not path.is_file():
        raise FileNotFoundError(f"no agent file {path}")
    if zipfile.is_zipfile(path):
        return _sb3_agent(path, num_actions, trust)
    return _jax_agent(path, num_actions, spec)


def _jax_agent(path: Path, num_actions: int, spec=None) -> Agent:
    try:
        params, network = jax_policy.load_agent(path)
    except ImportError as exc:
        raise ImportError(f"--agent {exc}") from exc
    from octax_gym.train.networks import ACTIONS  # flax is there: the params loaded

    if network.num_actions < num_actions or (network.num_actions != num_actions and network.num_actions != ACTIONS):
        raise ValueError(f"{path} plays {network.num_actions} actions; this game has {num_actions}")
    # A trainer's agent has an output per key (ACTIONS); the game takes its first `num_actions`.
    greedy = jax.jit(lambda obs: jnp.argmax(jax_policy.action_scores(params, obs[None], num_actions), axis=-1)[0])
    act = _fit_channels(lambda obs: int(greedy(jnp.asarray(obs))), network.channels)
    return _as_trained(act, path, spec) if network.mirror else act


def _as_trained(agent: Agent, path: Path, spec) -> Agent:
    """An agent trained with mirrored seats, in the player's plain two-player env (where people
    see and press what the game shows): from seat 1 (its player plane lit) it is shown the screens
    flipped across the game's axis and its action is mapped through `Seats.mirror_actions`, which
    is what `make_multi(..., mirror=True)` does for the seat it trained in."""
    from octax_core.env.multi import MIRROR_AXIS

    seats = getattr(spec, "seats", None)
    if seats is None or seats.mirror is None:
        raise ValueError(f"{path} was trained with mirrored seats (--mirror); "
                         f"{getattr(spec, 'id', 'this game')} has none to play it in")
    axis, to_game = MIRROR_AXIS[seats.mirror], np.asarray(seats.mirror_actions)

    def mirrored(obs: np.ndarray) -> int:
        obs = np.asarray(obs)
        if not obs[-1].any():  # seat 0 sees the game as it is, mirrored or not
            return agent(obs)
        return int(to_game[agent(np.concatenate([np.flip(obs[:-1], axis=axis), obs[-1:]]))])
    return mirrored


def _sb3_agent(path: Path, num_actions: int, trust: bool) -> Agent:
    try:
        import stable_baselines3  # noqa: F401
    except ImportError as exc:
        raise ImportError(f"--agent {path.name} (an SB3 zip) needs stable-baselines3: "
                          f"pip install 'octax-gym[sb3]' ({exc})") from exc
    if trust:
        model, channels, actions = _trusted_sb3_model(path)
    else:
        from octax_gym.play.sb3_zip import load_policy
        model, channels, actions = load_policy(path)
    if actions != num_actions:
        raise ValueError(f"{path} plays {actions} actions; this game has {num_actions}")
    return _fit_channels(lambda obs: int(np.asarray(model.predict(obs, deterministic=True)[0]).reshape(-1)[0]),
                         channels)


def _trusted_sb3_model(path: Path):
    """SB3's own loader (it unpickles the file): the model, its input planes and its actions."""
    from stable_baselines3 import A2C, DQN, PPO

    errors = []
    for algorithm in (PPO, A2C, DQN):
        try:
            model = algorithm.load(str(path), device="cpu")
            break
        except Exception as exc:  # the wrong algorithm's policy class, or not a model at all
            errors.append(f"{algorithm.__name__}: {exc!r}"[:200])
    else:
        raise ValueError(f"{path} is not a Stable-Baselines3 PPO, A2C or DQN model ({'; '.join(errors)})")
    return model, int(model.observation_space.shape[0]), getattr(model.action_space, "n", "?")


def _fit_channels(act: Callable[[np.ndarray], int], channels: int) -> Agent:
    """An agent of `channels` input planes fed a seat's observation: one-player frames to a
    self-play agent (a zero player plane added: seat 0's) or a two-player one to a one-player agent
    (the player plane dropped)."""
    def agent(obs: np.ndarray) -> int:
        obs = np.asarray(obs)
        if obs.shape[0] > channels:
            obs = obs[:channels]
        elif obs.shape[0] < channels:
            obs = np.concatenate([obs, np.zeros((channels - obs.shape[0], *obs.shape[1:]), obs.dtype)])
        return agent.act(obs)

    agent.act = act
    agent.channels = channels
    return agent
