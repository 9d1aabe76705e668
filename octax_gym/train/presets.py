"""Named settings for `TrainConfig`: the paper's (for a GPU) and a small one for a CPU.

A preset is a dict of field values per algorithm; flags given on the command line override it.
"paper" is the octax paper's setup (Radji et al., section 5 and its Rejax-based code): 512 envs x
32-step rollouts, 4 epochs of 32 minibatches, Adam 5e-4 (constant), clip 0.2, GAE 0.95, entropy
0.01, value 0.5, grad norm 0.5 for PPO; PQN with LayerNorm, lambda 0.9, epsilon 1.0 -> 0.05 over
the first 10%, grad norm 10 (PQN's own; the paper gives none); 5M steps an agent, evaluated every
131,072 steps on 128 episodes. "cpu" keeps the algorithms' settings and scales the batch down to
what two CPU cores train in minutes (64 envs, 8 minibatches; the runs of docs/results.md).
"""

from __future__ import annotations

import dataclasses

from octax_gym.train.config import ALGORITHMS, TrainConfig

_PAPER_COMMON = dict(total_steps=5_000_000, num_envs=512, num_steps=32, update_epochs=4, num_minibatches=32,
                     learning_rate=5e-4, anneal_lr=False, gamma=0.99, eval_every=131_072, eval_envs=128)
PAPER = {
    "ppo": dict(_PAPER_COMMON, max_grad_norm=0.5, gae_lambda=0.95, clip_eps=0.2, clip_value_loss=True,
                vf_coef=0.5, ent_coef=0.01),
    "pqn": dict(_PAPER_COMMON, max_grad_norm=10.0, q_lambda=0.9, epsilon_start=1.0, epsilon_finish=0.05,
                epsilon_fraction=0.1, eval_epsilon=0.005),
}
PAPER["multitask"] = PAPER["ppo"]  # the multi-task agent learns with PPO
# Self-play learns with PPO too (the paper has no self-play: its settings, with pure self-play's pool 0).
PAPER["selfplay"] = dict(PAPER["ppo"], pool=0, pool_prob=0.5)
# Offline (not the paper's): an update draws 1,024 transitions and takes 8 Adam steps of 128 on them,
# 2,000 steps in all (the batch and steps of the offline example it replaces); one setting for both presets.
_OFFLINE = dict(total_steps=256_000, num_envs=128, num_steps=8, update_epochs=1, num_minibatches=8,
                learning_rate=3e-4, anneal_lr=False, gamma=0.99, max_grad_norm=10.0, eval_every=64_000, eval_envs=32,
                eval_epsilon=0.005, cql_alpha=1.0, target_every=64)
_CPU_SCALE = dict(total_steps=655_360, num_envs=64, num_steps=32, num_minibatches=8, eval_every=65_536,
                  eval_envs=32)
CPU = {algorithm: dict(settings, **_CPU_SCALE) for algorithm, settings in PAPER.items()}
PAPER.update(bc=_OFFLINE, cql=_OFFLINE)
CPU.update(bc=_OFFLINE, cql=_OFFLINE)
PRESETS = {"paper": PAPER, "cpu": CPU}


def preset(name: str, algorithm: str, **overrides) -> TrainConfig:
    """The `name` preset's config for `algorithm`, with `overrides` (other fields) applied and checked.

    Raises:
        ValueError: an unknown preset or algorithm (the message lists the valid ones), or a bad value.
    """
    if name not in PRESETS:
        raise ValueError(f"preset must be one of {', '.join(PRESETS)}, got {name!r}")
    if algorithm not in ALGORITHMS:
        raise ValueError(f"algorithm must be one of {', '.join(ALGORITHMS)}, got {algorithm!r}")
    values = {**PRESETS[name][algorithm], **overrides, "algorithm": algorithm}
    return dataclasses.replace(TrainConfig(), **values).check()
