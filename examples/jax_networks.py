"""The octax paper's networks in flax, shared by the pure-JAX PPO and PQN examples.

    torso = ConvTorso()                   # (B, 4, 32, 64) uint8 frames -> (B, 1024) features
    ActorCritic(num_actions)(obs)         # PPO: logits (B, A), values (B,)
    QNetwork(num_actions)(obs)            # PQN: Q-values (B, A)

Both agents read the frames with the same convolutional torso, as the paper does "for fair
comparison" (Radji et al., section 5): three VALID convolutions of 32, 64 and 64 filters, kernels
(8, 4), 4, 3 and strides (4, 2), 2, 1, ReLU after each, then one 256-unit ReLU layer per head. PQN
adds LayerNorm before the ReLU of its hidden layer (the paper: "and LayerNorm for PQN"; PQN relies
on it in place of a target network, Gallici et al., 2024). The torch version of the same network
is `octax_gym.networks`.
"""

from __future__ import annotations

import math

import flax.linen as nn
import jax
import jax.numpy as jnp

HIDDEN = 256


def orthogonal(scale: float):
    return nn.initializers.orthogonal(scale)


def conv_valid(x: jax.Array, kernel: jax.Array, strides: tuple[int, int]) -> jax.Array:
    """A VALID, NHWC convolution as one matmul over strided slices (im2col), same values as
    `lax.conv_general_dilated`.

    Why not `nn.Conv`: on XLA's CPU backend the kernel gradient of a convolution inside a loop
    (our minibatch `lax.scan`) ran 50-130x slower than outside one (measured on this project's
    layers, jax 0.10), which made a PPO update 40x slower. Slices and a matmul differentiate into
    pads and matmuls, which run at full speed anywhere.
    """
    kh, kw, cin, cout = kernel.shape
    (sh, sw), (h, w) = strides, x.shape[1:3]
    oh, ow = (h - kh) // sh + 1, (w - kw) // sw + 1
    patches = [x[:, i:i + sh * (oh - 1) + 1:sh, j:j + sw * (ow - 1) + 1:sw]
               for i in range(kh) for j in range(kw)]
    return jnp.concatenate(patches, axis=-1) @ kernel.reshape(kh * kw * cin, cout)


class Conv(nn.Module):
    """`nn.Conv(features, kernel_size, strides, padding="VALID")`, computed by `conv_valid`."""

    features: int
    kernel_size: tuple[int, int]
    strides: tuple[int, int]

    @nn.compact
    def __call__(self, x: jax.Array) -> jax.Array:
        shape = (*self.kernel_size, x.shape[-1], self.features)
        kernel = self.param("kernel", orthogonal(math.sqrt(2)), shape)
        bias = self.param("bias", nn.initializers.zeros, (self.features,))
        return conv_valid(x, kernel, self.strides) + bias


class ConvTorso(nn.Module):
    """The paper's feature extractor: (B, F, 32, 64) frames -> (B, 1024) for F = 4."""

    @nn.compact
    def __call__(self, obs: jax.Array) -> jax.Array:
        # (B, F, H=32, W=64) -> (B, 64, 32, F): the paper's (64, 32) image with the F frames as
        # channels (NHWC), so its (8, 4) kernel spans 8 columns and 4 rows.
        x = jnp.transpose(obs, (0, 3, 2, 1)).astype(jnp.float32)
        for features, kernel, strides in ((32, (8, 4), (4, 2)), (64, (4, 4), (2, 2)), (64, (3, 3), (1, 1))):
            x = nn.relu(Conv(features, kernel, strides)(x))  # 15x15x32 -> 6x6x64 -> 4x4x64
        return x.reshape(x.shape[0], -1)


class ActorCritic(nn.Module):
    """PPO's network: ConvTorso, then separate actor and critic heads of one 256-unit ReLU layer each.

    It also reads (frames, game) pairs (the multi-task example): with `num_games` > 0 the game's
    one-hot joins the torso's features before the heads, with 0 the game is not read.
    """

    num_actions: int
    num_games: int = 0

    @nn.compact
    def __call__(self, obs) -> tuple[jax.Array, jax.Array]:
        """Returns logits (B, num_actions) and values (B,)."""
        frames, game = obs if isinstance(obs, tuple) else (obs, None)
        features = ConvTorso()(frames)
        if self.num_games:
            features = jnp.concatenate([features, jax.nn.one_hot(game, self.num_games, dtype=features.dtype)], -1)
        # Orthogonal init as in CleanRL: small policy outputs start the policy near uniform.
        actor = nn.relu(nn.Dense(HIDDEN, kernel_init=orthogonal(math.sqrt(2)))(features))
        logits = nn.Dense(self.num_actions, kernel_init=orthogonal(0.01))(actor)
        critic = nn.relu(nn.Dense(HIDDEN, kernel_init=orthogonal(math.sqrt(2)))(features))
        value = nn.Dense(1, kernel_init=orthogonal(1.0))(critic)
        return logits, value[:, 0]


class QNetwork(nn.Module):
    """PQN's network: ConvTorso, then one 256-unit layer with LayerNorm and ReLU, then a Q-value per action.

    LayerNorm on the hidden layer is what lets PQN learn without a target network or replay
    buffer (Gallici et al., 2024); the octax paper's PQN has it on that layer and not in the torso.
    """

    num_actions: int

    @nn.compact
    def __call__(self, obs: jax.Array) -> jax.Array:
        """Returns Q-values (B, num_actions)."""
        features = ConvTorso()(obs)
        hidden = nn.Dense(HIDDEN, kernel_init=orthogonal(math.sqrt(2)))(features)
        hidden = nn.relu(nn.LayerNorm()(hidden))
        return nn.Dense(self.num_actions, kernel_init=orthogonal(1.0))(hidden)
