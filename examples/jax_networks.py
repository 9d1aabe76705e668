"""The octax paper's networks, for the examples that still build their own loops (multi-task,
self-play, offline): the package's one network module, `octax_gym.train.networks`, re-exported.

    ActorCritic(num_actions)(obs)         # PPO: logits (B, A), values (B,)
    QNetwork(num_actions)(obs)            # PQN: Q-values (B, A)
"""

from octax_gym.train.networks import (HIDDEN, ActorCritic, Conv, ConvTorso, QNetwork, conv_valid,  # noqa: F401
                                      orthogonal)
