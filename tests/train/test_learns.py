"""The trainer learns: 131,072 steps of PPO on Airplane (64 envs, the cpu preset) end at an evaluation
return of at least 1.0, where the committed random baseline is 0.31 (about 90 s on two cores)."""

from __future__ import annotations

import pytest

pytest.importorskip("flax")
from octax_gym.train import preset, train  # noqa: E402


@pytest.mark.slow  # ~90 s of training on two CPU cores; CI's test-slow runs it
def test_ppo_learns_airplane(tmp_path):
    config = preset("cpu", "ppo", games=("Airplane",), total_steps=131_072, eval_every=0, eval_envs=32)
    summary = train(config, tmp_path, progress=False)
    final = summary["games"]["Airplane"]
    assert final["random"] == pytest.approx(0.3125)
    assert final["mean"] >= 1.0, final
