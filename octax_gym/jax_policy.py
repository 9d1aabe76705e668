"""The pure-JAX examples' trained networks, run from their saved params without the examples.

`examples/train_jax_ppo.py`, `train_jax_pqn.py` and `train_jax_selfplay.py` save
`flax.serialization.to_bytes` of `examples/jax_networks.py`'s `ActorCritic` or `QNetwork`
(`params.msgpack`). Here those params are read back and the network's forward pass is computed in
plain JAX from its parameter names (PQN's has a LayerNorm), so `octax-gym play --agent` and the
dataset suite (`octax_gym.datasets.suite`) run trained agents with no import of the examples.
Reading the msgpack needs flax (the `train` extra); nothing else here does.

    params = load_params("runs/airplane/params.msgpack")
    net = describe(params)                    # Network(kind="actor_critic", channels=4, num_actions=2)
    act = sampling_policy(params, seed=0)     # numpy (B, 4, 32, 64) -> numpy (B,) actions
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np


class Network(NamedTuple):
    """What a params file holds: its network, input planes and actions."""

    kind: str  # "actor_critic" (PPO, self-play) or "q_network" (PQN)
    channels: int  # input planes: the frames (plus a player plane for self-play agents)
    num_actions: int


def load_params(path) -> dict:
    """The params saved at `path` by the JAX examples, as nested dicts of JAX arrays.

    Raises:
        ImportError: flax is missing. ValueError: not params of the examples' networks.
    """
    path = Path(path)
    try:
        import flax.serialization
    except ImportError as exc:
        raise ImportError(f"{path.name} (JAX params) needs flax: pip install 'octax-gym[train]' ({exc})") from exc
    try:
        params = flax.serialization.msgpack_restore(path.read_bytes())
        describe(params)
    except Exception as exc:  # msgpack's and KeyError's: not the examples' params
        raise ValueError(f"{path} is not params saved by the JAX examples (flax msgpack of ActorCritic or "
                         f"QNetwork): {exc!r}") from None
    return jax.tree.map(jnp.asarray, params)


def describe(params) -> Network:
    p = params["params"]
    kind = "q_network" if "LayerNorm_0" in p else "actor_critic"
    return Network(kind, int(p["ConvTorso_0"]["Conv_0"]["kernel"].shape[2]), int(p["Dense_1"]["kernel"].shape[1]))


def action_scores(params, obs: jax.Array) -> jax.Array:
    """The policy's logits (ActorCritic) or Q-values (QNetwork), (B, num_actions), of uint8 (B, C, 32, 64)."""
    return (q_values if "LayerNorm_0" in params["params"] else actor_critic_logits)(params, obs)


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


def sampling_policy(params, seed: int) -> Callable[[np.ndarray], np.ndarray]:
    """A batched policy for `collect_dataset`: actions sampled from the softmax of the network's
    scores (the stochastic policy PPO trains and is evaluated with), from a key chain of `seed`
    (call i folds i into it), so the same seed gives the same actions."""
    key = jax.random.key(seed)
    draw = jax.jit(lambda params, key, obs: jax.random.categorical(key, action_scores(params, obs)).astype(jnp.int32))
    calls = iter(range(2 ** 31))

    def act(obs: np.ndarray) -> np.ndarray:
        return np.asarray(draw(params, jax.random.fold_in(key, next(calls)), jnp.asarray(obs)))

    act.__name__ = "ppo_policy"
    return act


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
