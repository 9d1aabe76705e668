"""Trained agents for `octax-gym play --agent PATH`: a function of one seat's observation -> action.

Two formats:

* `*.msgpack`: the params the pure-JAX examples save (`examples/train_jax_ppo.py`,
  `train_jax_pqn.py`, `train_jax_selfplay.py`: `flax.serialization.to_bytes` of
  `examples/jax_networks.py`'s `ActorCritic` or `QNetwork`). The network is read from the params'
  names (PQN's has a LayerNorm) and run here in plain JAX, so the examples need not be importable;
  it plays greedily (the largest logit or Q-value). Needs flax (the `train` extra).
* `*.zip`: a Stable-Baselines3 model (`model.save(...)`: PPO, A2C or DQN), played with
  `model.predict(obs, deterministic=True)`. Needs the `sb3` extra.

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

Agent = Callable[[np.ndarray], int]


def load_agent(path, num_actions: int) -> Agent:
    """The agent saved at `path` (.msgpack or .zip) for a game of `num_actions` actions.

    Raises:
        FileNotFoundError: no such file. ValueError: an unknown format, or params that do not
        fit the game. ImportError: flax or stable-baselines3 missing.
    """
    path = Path(path).expanduser()
    if not path.is_file():
        raise FileNotFoundError(f"no agent file {path}")
    if zipfile.is_zipfile(path):
        return _sb3_agent(path, num_actions)
    return _jax_agent(path, num_actions)


# --- the JAX examples' networks -----------------------------------------------------------------


def _conv_valid(x, kernel, strides):
    """`examples/jax_networks.conv_valid`: a VALID NHWC convolution as one matmul over slices."""
    kh, kw, cin, cout = kernel.shape
    (sh, sw), (h, w) = strides, x.shape[1:3]
    oh, ow = (h - kh) // sh + 1, (w - kw) // sw + 1
    patches = [x[:, i:i + sh * (oh - 1) + 1:sh, j:j + sw * (ow - 1) + 1:sw] for i in range(kh) for j in range(kw)]
    return jnp.concatenate(patches, axis=-1) @ kernel.reshape(kh * kw * cin, cout)


def _torso(p, obs):
    x = jnp.transpose(obs, (0, 3, 2, 1)).astype(jnp.float32)
    for i, strides in enumerate(((4, 2), (2, 2), (1, 1))):
        conv = p[f"Conv_{i}"]
        x = jax.nn.relu(_conv_valid(x, conv["kernel"], strides) + conv["bias"])
    return x.reshape(x.shape[0], -1)


def _dense(p, x):
    return x @ p["kernel"] + p["bias"]


def _layer_norm(p, x, eps=1e-6):
    mean = x.mean(-1, keepdims=True)
    var = ((x - mean) ** 2).mean(-1, keepdims=True)
    return (x - mean) / jnp.sqrt(var + eps) * p["scale"] + p["bias"]


def actor_critic_logits(params, obs):
    """`ActorCritic.apply(params, obs)[0]` of examples/jax_networks.py."""
    p = params["params"]
    features = _torso(p["ConvTorso_0"], obs)
    return _dense(p["Dense_1"], jax.nn.relu(_dense(p["Dense_0"], features)))


def q_values(params, obs):
    """`QNetwork.apply(params, obs)` of examples/jax_networks.py."""
    p = params["params"]
    hidden = _dense(p["Dense_0"], _torso(p["ConvTorso_0"], obs))
    return _dense(p["Dense_1"], jax.nn.relu(_layer_norm(p["LayerNorm_0"], hidden)))


def _jax_agent(path: Path, num_actions: int) -> Agent:
    try:
        import flax.serialization
    except ImportError as exc:
        raise ImportError(f"--agent {path.name} (JAX params) needs flax: pip install 'octax-gym[train]' ({exc})") from exc
    try:
        params = flax.serialization.msgpack_restore(path.read_bytes())
        p = params["params"]
        network = q_values if "LayerNorm_0" in p else actor_critic_logits
        channels = int(p["ConvTorso_0"]["Conv_0"]["kernel"].shape[2])
        outputs = int(p["Dense_1"]["kernel"].shape[1])
    except Exception as exc:  # msgpack's and KeyError's: not the examples' params
        raise ValueError(f"{path} is not params saved by the JAX examples (flax msgpack of ActorCritic or "
                         f"QNetwork): {exc!r}") from None
    if outputs != num_actions:
        raise ValueError(f"{path} plays {outputs} actions; this game has {num_actions}")
    params = jax.tree.map(jnp.asarray, params)
    greedy = jax.jit(lambda obs: jnp.argmax(network(params, obs[None]), axis=-1)[0])
    return _fit_channels(lambda obs: int(greedy(jnp.asarray(obs))), channels)


def _sb3_agent(path: Path, num_actions: int) -> Agent:
    try:
        from stable_baselines3 import A2C, DQN, PPO
    except ImportError as exc:
        raise ImportError(f"--agent {path.name} (an SB3 zip) needs stable-baselines3: "
                          f"pip install 'octax-gym[sb3]' ({exc})") from exc
    errors = []
    for algorithm in (PPO, A2C, DQN):
        try:
            model = algorithm.load(str(path), device="cpu")
            break
        except Exception as exc:  # the wrong algorithm's policy class, or not a model at all
            errors.append(f"{algorithm.__name__}: {exc!r}"[:200])
    else:
        raise ValueError(f"{path} is not a Stable-Baselines3 PPO, A2C or DQN model ({'; '.join(errors)})")
    if getattr(model.action_space, "n", None) != num_actions:
        raise ValueError(f"{path} plays {getattr(model.action_space, 'n', '?')} actions; this game has {num_actions}")
    channels = int(model.observation_space.shape[0])
    return _fit_channels(lambda obs: int(np.asarray(model.predict(obs, deterministic=True)[0]).reshape(-1)[0]),
                         channels)


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
