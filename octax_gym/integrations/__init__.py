"""The RL libraries' adapters. Each imports its library (and torch) at its own import, so this
package imports none of them: `import octax_gym` stays free of torch, SB3 and TorchRL.

    sb3.py      a stable-baselines3 VecEnv and the paper's CNN extractor (public as octax_gym.sb3)
    torchrl.py  a native batched TorchRL EnvBase (public as octax_gym.torchrl)
"""
