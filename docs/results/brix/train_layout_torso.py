"""The conv torso in the input layout of the octax paper's code, for an A/B run of `octax-gym train`.

The paper's PPO (octax/agents/ppo.py + wrappers.py at riiswa/octax f1cb740) gives flax nn.Conv the
gymnax observation (B, 4, 32, 64) as NHWC: height = the 4 frames, width = the 32 rows, channels =
the 64 columns, SAME padding. Ours transposes to (B, 64, 32, 4) with VALID padding. LAYOUT=paper
swaps in the paper's layout (same kernels, strides, widths and init as ours), LAYOUT=ours leaves
the package alone. Imported by train_layout.py (training) and eval_agent.py.
"""
import os, sys
import jax, jax.numpy as jnp
import flax.linen as nn
from octax_gym.train import networks


def same_pad(x, kernel, strides):
    pads = [(0, 0)]
    for n, k, s in zip(x.shape[1:3], kernel, strides):
        out = -(-n // s)
        total = max((out - 1) * s + k - n, 0)
        pads.append((total // 2, total - total // 2))
    return jnp.pad(x, pads + [(0, 0)])


class PaperLayoutTorso(nn.Module):
    @nn.compact
    def __call__(self, obs):
        x = obs.astype(jnp.float32)  # (B, 4, 32, 64): H = frames, W = rows, C = columns
        for features, kernel, strides in ((32, (8, 4), (4, 2)), (64, (4, 4), (2, 2)), (64, (3, 3), (1, 1))):
            x = nn.relu(networks.Conv(features, kernel, strides)(same_pad(x, kernel, strides)))
        return x.reshape(x.shape[0], -1)  # (B, 1, 8, 64) -> (B, 512)


if os.environ.get("LAYOUT") == "paper":
    networks.ConvTorso = PaperLayoutTorso
    print("torso: the paper's layout", file=sys.stderr)
else:
    print("torso: ours", file=sys.stderr)

