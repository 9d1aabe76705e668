"""The octax paper's networks in flax: one convolutional torso, PPO's actor-critic head, PQN's Q head.

    ActorCritic()(obs)        # (B, 4, 32, 64) uint8 frames -> logits (B, ACTIONS), values (B,)
    QNetwork()(obs)           # -> Q-values (B, ACTIONS)
    masked(scores, legal)     # the actions a game does not take pushed to ILLEGAL

Both agents read the frames with the same torso, as the paper does "for fair comparison" (Radji
et al., section 5): three convolutions of 32, 64 and 64 filters, kernels (8, 4), 4, 3 and strides
(4, 2), 2, 1, ReLU after each, then one 256-unit ReLU layer per head. The torso reads the frames in
one of two layouts (`LAYOUTS`, `--network-layout`): "image" (the default), the paper's text, the
64 x 32 screen with the frames as channels; or "paper", the paper's released code, which hands
flax the (F, 32, 64) frames as one NHWC image, so it convolves over frames x rows with the 64
columns as channels (SAME padding). They differ in what they learn: on Brix the paper's layout
learns in 131k CPU steps and ours stays at random level (docs/results/brix.md). PQN adds LayerNorm
before the ReLU of its hidden layer (the paper: "and LayerNorm for PQN"; PQN relies on it in place
of a target network, Gallici et al., 2024). `octax_gym.networks` is the torch twin (SB3, TorchRL).

Why one output width for every game (`ACTIONS` = 17: no-op plus the 16 keys, the most any
registered game takes): an agent's network then does not depend on which games share its run, so
agent (game, seed) of a many-game run draws the same initial weights and the same random numbers
as a run of that game alone, and learns exactly what it learns alone. A game's actions past its
own are masked (`masked`) before sampling, log-probs, entropy and argmax.
"""

from __future__ import annotations

import functools
import math

import flax.linen as nn
import jax
import jax.numpy as jnp
import numpy as np

from octax_gym.train.config import NETWORK_LAYOUTS as LAYOUTS  # how the torso reads the frames (ConvTorso)

HIDDEN = 256
ACTIONS = 17  # no-op + 16 keys: every game's actions fit (octax_core's games take at most 16 keys)
ILLEGAL = -1e9  # a masked score: exp() of it is 0 and 0 * ILLEGAL is 0 (with -inf the entropy is nan)


def masked(scores: jax.Array, legal: jax.Array) -> jax.Array:
    """`scores` (B, A) with the actions `legal` ((A,) or (B, A) bool) marks False set to ILLEGAL."""
    return jnp.where(legal, scores, ILLEGAL)


def legal_actions(num_actions: int) -> jax.Array:
    """bool (ACTIONS,): the first `num_actions` actions (a game's own: no-op, then its keys)."""
    return jnp.arange(ACTIONS) < num_actions


def orthogonal(scale: float):
    return nn.initializers.orthogonal(scale)


def conv_valid(x: jax.Array, kernel: jax.Array, strides: tuple[int, int]) -> jax.Array:
    """A VALID, NHWC convolution as its patch matrix times the kernel (im2col), same values as
    `lax.conv_general_dilated`.

    Why not `nn.Conv`: on XLA's CPU backend the kernel gradient of a convolution inside a loop
    (our minibatch `lax.scan`) ran 50-130x slower than outside one (measured on this project's
    layers, jax 0.10), which made a PPO update 40x slower. A patch matrix and a matmul
    differentiate into pads and matmuls, which run at full speed anywhere.
    """
    kh, kw, cin, cout = kernel.shape
    return patches(x, (kh, kw), tuple(strides)) @ kernel.reshape(kh * kw * cin, cout)


@functools.partial(jax.custom_vjp, nondiff_argnums=(1, 2))
def patches(x: jax.Array, kernel_size: tuple[int, int], strides: tuple[int, int]) -> jax.Array:
    """(B, H, W, C) -> (B, OH, OW, KH * KW * C): each output position's input patch, kernel row
    major, then column, then channel (the rows of `kernel.reshape(kh * kw * cin, cout)`).

    Built by one gather with a constant index; its gradient is the transpose of one strided slice
    per kernel offset (`_sliced_patches`). Both ways give the same bits, forward and backward,
    but each is the cheaper one in its direction: XLA compiles the 32-way concatenate of the first
    layer's slices slowly, and runs the gather's own gradient (a scatter-add) slower than the
    slices' pads (docs/training.md has the measurements).
    """
    (kh, kw), (sh, sw), (b, h, w, cin) = kernel_size, strides, x.shape
    oh, ow = (h - kh) // sh + 1, (w - kw) // sw + 1
    rows = np.arange(oh)[:, None, None, None] * sh + np.arange(kh)[None, None, :, None]
    cols = np.arange(ow)[None, :, None, None] * sw + np.arange(kw)[None, None, None, :]
    return x.reshape(b, h * w, cin)[:, (rows * w + cols).reshape(-1)].reshape(b, oh, ow, kh * kw * cin)


def _sliced_patches(x: jax.Array, kernel_size: tuple[int, int], strides: tuple[int, int]) -> jax.Array:
    """`patches` as one strided slice per kernel offset, concatenated."""
    (kh, kw), (sh, sw), (h, w) = kernel_size, strides, x.shape[1:3]
    oh, ow = (h - kh) // sh + 1, (w - kw) // sw + 1
    return jnp.concatenate([x[:, i:i + sh * (oh - 1) + 1:sh, j:j + sw * (ow - 1) + 1:sw]
                            for i in range(kh) for j in range(kw)], axis=-1)


def _patches_forward(x, kernel_size, strides):
    return patches(x, kernel_size, strides), x.shape  # the backward needs only the shape


def _patches_backward(kernel_size, strides, shape, cotangent):
    transpose = jax.linear_transpose(lambda x: _sliced_patches(x, kernel_size, strides),
                                     jax.ShapeDtypeStruct(shape, cotangent.dtype))
    return transpose(cotangent)


patches.defvjp(_patches_forward, _patches_backward)


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


LAYERS = ((32, (8, 4), (4, 2)), (64, (4, 4), (2, 2)), (64, (3, 3), (1, 1)))  # (filters, kernel, strides)


class ConvTorso(nn.Module):
    """The paper's feature extractor: (B, F, 32, 64) frames -> (B, 1024) ("image") or (B, 512)
    ("paper", for F <= 8)."""

    layout: str = "image"

    @nn.compact
    def __call__(self, obs: jax.Array) -> jax.Array:
        if self.layout not in LAYOUTS:
            raise ValueError(f"layout must be one of {', '.join(LAYOUTS)}, got {self.layout!r}")
        paper = self.layout == "paper"
        # image: (B, F, H=32, W=64) -> (B, 64, 32, F), the paper's (64, 32) image with the F frames
        # as channels (NHWC), so its (8, 4) kernel spans 8 columns and 4 rows; VALID padding:
        # 15x15x32 -> 6x6x64 -> 4x4x64. paper: (B, F, 32, 64) as it is, NHWC with height the F
        # frames, width the 32 rows and the 64 columns as channels; SAME padding: 1x16x32 -> 1x8x64 -> 1x8x64.
        x = (obs if paper else jnp.transpose(obs, (0, 3, 2, 1))).astype(jnp.float32)
        for features, kernel, strides in LAYERS:
            x = nn.relu(Conv(features, kernel, strides)(same_padded(x, kernel, strides) if paper else x))
        return x.reshape(x.shape[0], -1)


def same_padded(x: jax.Array, kernel_size: tuple[int, int], strides: tuple[int, int]) -> jax.Array:
    """(B, H, W, C) zero-padded as flax's (and TensorFlow's) SAME padding pads it: a VALID
    convolution of the result is the SAME convolution of `x` (ceil(H / stride) outputs)."""
    pads = [(0, 0)]
    for size, kernel, stride in zip(x.shape[1:3], kernel_size, strides):
        total = max((-(-size // stride) - 1) * stride + kernel - size, 0)
        pads.append((total // 2, total - total // 2))
    return jnp.pad(x, pads + [(0, 0)])


class ActorCritic(nn.Module):
    """PPO's network: ConvTorso, then separate actor and critic heads of one 256-unit ReLU layer each.

    It also reads (frames, game) pairs (a multi-task agent): with `num_games` > 0 the game's
    one-hot joins the torso's features before the heads, with 0 the game is not read.
    """

    num_actions: int = ACTIONS
    num_games: int = 0
    layout: str = "image"  # the torso's (LAYOUTS)

    @nn.compact
    def __call__(self, obs) -> tuple[jax.Array, jax.Array]:
        """Returns logits (B, num_actions) and values (B,)."""
        frames, game = obs if isinstance(obs, tuple) else (obs, None)
        features = ConvTorso(self.layout)(frames)
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

    num_actions: int = ACTIONS
    layout: str = "image"  # the torso's (LAYOUTS)

    @nn.compact
    def __call__(self, obs: jax.Array) -> jax.Array:
        """Returns Q-values (B, num_actions)."""
        features = ConvTorso(self.layout)(obs)
        hidden = nn.Dense(HIDDEN, kernel_init=orthogonal(math.sqrt(2)))(features)
        hidden = nn.relu(nn.LayerNorm()(hidden))
        return nn.Dense(self.num_actions, kernel_init=orthogonal(1.0))(hidden)


def network_for(params) -> nn.Module:
    """The module that `params` (a saved `{"params": ...}` tree) belongs to, with its own output
    width and layout: QNetwork where the hidden layer has a LayerNorm, else ActorCritic (a
    multi-task agent's game one-hot read from its first hidden layer's input width)."""
    p = params["params"]
    width, layout = int(p["Dense_1"]["kernel"].shape[1]), layout_of(p["ConvTorso_0"])
    if "LayerNorm_0" in p:
        return QNetwork(width, layout)
    torso_width = _torso_width(p["ConvTorso_0"], layout)
    return ActorCritic(width, int(p["Dense_0"]["kernel"].shape[0]) - torso_width, layout)


def layout_of(torso) -> str:
    """A torso's layout, read from its first kernel's input channels: the frames in "image"
    (one to a few), the screen's 64 columns in "paper"."""
    return "paper" if int(torso["Conv_0"]["kernel"].shape[2]) >= 32 else "image"


def _torso_width(torso, layout: str) -> int:
    """The torso's output width on a (32, 64) screen: 4 x 4 (image) or 1 x 8 (paper, up to 8
    frames) x the last convolution's filters."""
    return (16 if layout == "image" else 8) * int(torso["Conv_2"]["kernel"].shape[-1])


def scores_of(network: nn.Module, params, obs) -> jax.Array:
    """The action scores of either network: ActorCritic's logits, QNetwork's Q-values."""
    out = network.apply(params, obs)
    return out[0] if isinstance(out, tuple) else out
