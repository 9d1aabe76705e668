"""The Octax paper's actor-critic network as plain torch modules, shared by the TorchRL and SB3 examples.

    net = ActorCritic(num_actions=3)                 # frames=4
    logits, value = net(obs)                         # obs: uint8 (B, 4, 32, 64) -> (B, 3), (B, 1)

The torso is the paper's CNN (Radji et al., 2025, the PPO agent of riiswa/octax): three convolutions
with 32, 64, 64 filters, kernels (8, 4), 4, 3 and strides (4, 2), 2, 1, ReLU after each. octax's env returns width-first
screens, (frames, 64, 32); ours are (frames, 32, 64), (H, W) as everywhere in this project, so the
torso swaps the last two axes before the first convolution and applies the kernels as stated,
with the frames as input channels and no padding:
(4, 64, 32) -> (32, 15, 15) -> (64, 6, 6) -> (64, 4, 4) = 1024 features. Separate actor and critic
heads of one 256-unit ReLU layer each read the shared features.

Importing this module imports torch only.
"""

from __future__ import annotations

import torch
from torch import nn

FEATURES = 1024  # 64 channels x 4 x 4 after the third convolution
HIDDEN = 256


class OctaxCNN(nn.Module):
    """The paper's convolutional torso: (B, frames, 32, 64) -> (B, 1024) features.

    Args:
        frames: frames per observation (the env's frames_per_step), the input channels.
        obs_scale: the value of a lit pixel in the input (1 or 255); inputs are divided by it, so the
            convolutions see 0.0 / 1.0. Pass 1 when something upstream has already scaled them
            (Stable-Baselines3 divides uint8 images by 255 before its features extractor).

    Inputs may be uint8 or float, with any leading batch dimensions.
    """

    features_dim = FEATURES

    def __init__(self, frames: int = 4, obs_scale: int = 1):
        super().__init__()
        if obs_scale <= 0:
            raise ValueError(f"obs_scale must be positive (1 or 255), got {obs_scale!r}")
        self.frames, self.obs_scale = frames, obs_scale
        self.convs = nn.Sequential(
            nn.Conv2d(frames, 32, kernel_size=(8, 4), stride=(4, 2)), nn.ReLU(),
            nn.Conv2d(32, 64, kernel_size=4, stride=2), nn.ReLU(),
            nn.Conv2d(64, 64, kernel_size=3, stride=1), nn.ReLU(),
            nn.Flatten(),
        )

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        if obs.shape[-3:] != (self.frames, 32, 64):
            raise ValueError(f"OctaxCNN expects observations (..., {self.frames}, 32, 64), got {tuple(obs.shape)}")
        batch = obs.shape[:-3]
        x = obs.reshape(-1, self.frames, 32, 64).to(torch.float32)
        if self.obs_scale != 1:
            x = x / self.obs_scale
        # The paper's kernels are (width, height)-first: swap to (frames, 64, 32) as it sees the screen.
        features = self.convs(x.transpose(-1, -2))
        return features.reshape(*batch, FEATURES)


def head(out_features: int, in_features: int = FEATURES, hidden: int = HIDDEN) -> nn.Sequential:
    """One hidden ReLU layer, then a linear output: the paper's actor and critic heads."""
    return nn.Sequential(nn.Linear(in_features, hidden), nn.ReLU(), nn.Linear(hidden, out_features))


class ActorCritic(nn.Module):
    """The paper's agent: a shared `OctaxCNN` torso, an actor head (logits) and a critic head (value).

    Args:
        num_actions: size of the action space (the env's `single_action_space.n`).
        frames, obs_scale: as for `OctaxCNN`.

    Attributes:
        torso: the `OctaxCNN`. actor: 1024 -> 256 -> num_actions. critic: 1024 -> 256 -> 1.

    `forward(obs)` returns `(logits, value)`, shapes (B, num_actions) and (B, 1).
    """

    def __init__(self, num_actions: int, frames: int = 4, obs_scale: int = 1):
        super().__init__()
        self.torso = OctaxCNN(frames, obs_scale)
        self.actor = head(num_actions)
        self.critic = head(1)

    def forward(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        features = self.torso(obs)
        return self.actor(features), self.critic(features)
