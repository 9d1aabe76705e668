"""Gymnasium, Stable-Baselines3 and TorchRL adapters for the CHIP-8 core (`octax_core`).

Not written yet: this package is a placeholder for the Gymnasium layer, which comes in a later
issue. It will import `octax_core`, never the reverse, and will load torch, SB3 and TorchRL lazily.
"""
