"""`octax-gym play --agent FILE.zip` reads a Stable-Baselines3 zip as data: nothing in the file runs.

SB3's own loader unpickles (cloudpickle) the `data` entry, so a zip could run any command the
moment it was loaded (issue 38, item 1). These tests hand the loader zips whose pickles run
`touch <file>` and check the file never appears, and check that the zips SB3 writes for the
architectures this project trains still play exactly as `model.predict(deterministic=True)`.
"""

from __future__ import annotations

import io
import json
import os
import zipfile

import numpy as np
import pytest

pytest.importorskip("stable_baselines3", reason="SB3 zips need the sb3 extra")

import gymnasium  # noqa: E402
import torch  # noqa: E402
from stable_baselines3 import A2C, DQN, PPO  # noqa: E402
from stable_baselines3.common.save_util import data_to_json  # noqa: E402

from octax_gym.play.agents import load_agent  # noqa: E402
from octax_gym.sb3 import OctaxCNNExtractor, ppo_kwargs  # noqa: E402
from torch_threads import one_torch_thread  # noqa: E402,F401  (autouse: one torch thread)

FRAMES, ACTIONS = 4, 3


class Frames(gymnasium.Env):
    """An env with the spaces of `octax_gym.sb3`'s (uint8 0/255 frames): SB3 builds models on it
    without compiling a game."""

    def __init__(self, frames: int = FRAMES, actions: int = ACTIONS):
        self.observation_space = gymnasium.spaces.Box(0, 255, (frames, 32, 64), np.uint8)
        self.action_space = gymnasium.spaces.Discrete(actions)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return self.observation_space.sample(), {}

    def step(self, action):
        return self.observation_space.sample(), 0.0, False, False, {}


class RunsCommand:
    """Unpickles to `os.system(command)`: what a hostile agent file stores in place of a class."""

    def __init__(self, command: str):
        self.command = command

    def __reduce__(self):
        return os.system, (self.command,)


def _model(kind: str, frames: int = FRAMES):
    env = Frames(frames)
    if kind == "ppo":     # the project's PPO: ReLU, the 1024 conv features shared by both heads
        model = PPO("CnnPolicy", env, **{**ppo_kwargs(1, 1), "n_steps": 8, "batch_size": 8}, seed=0)
    elif kind == "a2c":   # SB3's defaults around our torso: Tanh, a 256-unit extractor head, RMSprop
        model = A2C("CnnPolicy", env, policy_kwargs={"features_extractor_class": OctaxCNNExtractor}, seed=0)
    elif kind == "ppo-separate":  # unshared torsos, frames not divided by 255, a deeper MLP
        model = PPO("CnnPolicy", env, n_steps=8, batch_size=8, seed=0,
                    policy_kwargs={"features_extractor_class": OctaxCNNExtractor, "share_features_extractor": False,
                                   "normalize_images": False, "net_arch": [64, 32]})
    elif kind == "dqn":
        model = DQN("CnnPolicy", env, buffer_size=10, seed=0,
                    policy_kwargs={"features_extractor_class": OctaxCNNExtractor, "net_arch": [32]})
        # After the ReLU layers every Q-value follows the frames' mean features, so one action wins
        # everywhere; shifting the output biases to centre the Q-values over the test frames makes
        # the greedy action depend on the frame.
        q = model.policy.q_net
        with torch.no_grad():
            latent = q.q_net[:-1](q.extract_features(torch.as_tensor(_frames()), q.features_extractor))
            q.q_net[-1].bias -= q.q_net[-1](latent).mean(0)
    else:
        raise ValueError(kind)
    return model


def _frames(frames: int = FRAMES, n: int = 64) -> np.ndarray:
    """Frames of a lit rectangle each, at random places and sizes (uniform noise looks the same to
    a CNN at any density: every frame would get one action)."""
    rng = np.random.default_rng(0)
    out = np.zeros((n, frames, 32, 64), np.uint8)
    for i in range(n):
        for f in range(frames):
            y, x, h, w = rng.integers(0, 24), rng.integers(0, 48), rng.integers(2, 9), rng.integers(2, 17)
            out[i, f, y:y + h, x:x + w] = 255
    return out


def _rewrite(path, **entries) -> None:
    """Replaces entries of the zip at `path` (bytes or str values)."""
    with zipfile.ZipFile(path) as archive:
        items = {name: archive.read(name) for name in archive.namelist()}
    items.update(entries)
    with zipfile.ZipFile(path, "w") as archive:
        for name, content in items.items():
            archive.writestr(name, content)


def _hostile_policy_class(marker) -> dict:
    """The `policy_class` entry exactly as SB3's `data_to_json` writes an object that unpickles to
    `os.system("touch marker")`."""
    return json.loads(data_to_json({"policy_class": RunsCommand(f"touch {marker}")}))["policy_class"]


@pytest.mark.parametrize("where", ["alone", "in a real model"])
def test_a_policy_class_that_runs_a_command_is_refused_and_never_run(tmp_path, where):
    marker = tmp_path / "ran"
    path = tmp_path / "agent.zip"
    if where == "alone":
        with zipfile.ZipFile(path, "w") as archive:
            archive.writestr("data", json.dumps({"policy_class": _hostile_policy_class(marker)}))
    else:
        _model("ppo").save(path)
        with zipfile.ZipFile(path) as archive:
            data = json.loads(archive.read("data"))
        data["policy_class"] = _hostile_policy_class(marker)
        _rewrite(path, data=json.dumps(data))
    with pytest.raises(ValueError, match="--trust-agent") as error:
        load_agent(path, ACTIONS)
    assert "Stable-Baselines3" in str(error.value)
    assert not marker.exists()


def test_no_pickle_in_data_is_ever_read(tmp_path):
    """Every pickle of `data` replaced by one that runs a command: the zip still plays, as SB3 played
    the original, and nothing ran."""
    marker = tmp_path / "ran"
    model = _model("ppo")
    path = tmp_path / "agent.zip"
    model.save(path)
    hostile = _hostile_policy_class(marker)[":serialized:"]
    with zipfile.ZipFile(path) as archive:
        data = json.loads(archive.read("data"))
    replaced = [key for key, value in data.items() if isinstance(value, dict) and ":serialized:" in value]
    assert {"policy_class", "policy_kwargs", "observation_space", "action_space"} <= set(replaced)
    for key in replaced:
        data[key][":serialized:"] = hostile
    _rewrite(path, data=json.dumps(data))
    agent = load_agent(path, ACTIONS)
    frames = _frames()
    assert [agent(o) for o in frames] == model.predict(frames, deterministic=True)[0].tolist()
    assert not marker.exists()


def test_weights_that_are_a_pickle_are_refused_and_never_run(tmp_path):
    marker = tmp_path / "ran"
    path = tmp_path / "agent.zip"
    _model("ppo").save(path)
    weights = io.BytesIO()
    torch.save({"action_net.weight": RunsCommand(f"touch {marker}")}, weights)
    _rewrite(path, **{"policy.pth": weights.getvalue()})
    with pytest.raises(ValueError, match="policy.pth") as error:
        load_agent(path, ACTIONS)
    assert "--trust-agent" in str(error.value)
    assert not marker.exists()


@pytest.mark.parametrize("kind", ["ppo", "a2c", "ppo-separate", "dqn"])
def test_sb3_zips_play_as_sb3_plays_them(tmp_path, kind):
    model = _model(kind)
    model.save(tmp_path / "agent.zip")
    frames = _frames()
    expected = model.predict(frames, deterministic=True)[0].tolist()
    assert len(set(expected)) > 1  # the comparison can tell networks apart
    agent = load_agent(tmp_path / "agent.zip", ACTIONS)
    assert agent.channels == FRAMES
    assert [agent(o) for o in frames] == expected
    with pytest.raises(ValueError, match="plays 3 actions; this game has 5"):
        load_agent(tmp_path / "agent.zip", 5)


def test_other_architectures_are_refused_unless_trusted(tmp_path):
    """A flat MLP policy is SB3's, not one this player rebuilds: refused by name; `trust=True` (the
    `--trust-agent` flag) hands it to SB3's own loader."""
    model = PPO("MlpPolicy", Frames(), n_steps=8, batch_size=8, seed=0)
    model.save(tmp_path / "mlp.zip")
    with pytest.raises(ValueError, match="OctaxCNNExtractor") as error:
        load_agent(tmp_path / "mlp.zip", ACTIONS)
    assert "FlattenExtractor" in str(error.value) and "--trust-agent" in str(error.value)
    agent = load_agent(tmp_path / "mlp.zip", ACTIONS, trust=True)
    frames = _frames(n=4)
    assert [agent(o) for o in frames] == model.predict(frames, deterministic=True)[0].tolist()


def test_damaged_zips_are_named_errors(tmp_path):
    path = tmp_path / "agent.zip"
    _model("ppo").save(path)
    with zipfile.ZipFile(path) as archive:
        data = json.loads(archive.read("data"))
    cases = {
        "not JSON": {"data": b"\x80not json"},
        "no policy.pth": {"policy.pth": None},
        "an activation": {"data": json.dumps({**data, "policy_kwargs": {
            **data["policy_kwargs"], "activation_fn": "<class 'torch.nn.modules.activation.GELU'>"}})},
        "frames": {"data": json.dumps({**data, "observation_space": {**data["observation_space"],
                                                                      "_shape": [2, 32, 64]}})},
        "bounds": {"data": json.dumps({**data, "observation_space": {**data["observation_space"],
                                                                      "high": "[[[1 1 1 ... 1 1 1]]]"}})},
        "deep JSON": {"data": b"[" * 100_000},
        "too many actions": {"data": json.dumps({**data, "action_space": {**data["action_space"], "n": "9" * 5000}})},
    }
    for name, entries in cases.items():
        broken = tmp_path / f"{name}.zip"
        with zipfile.ZipFile(path) as archive, zipfile.ZipFile(broken, "w") as out:
            for item in archive.namelist():
                content = entries.get(item, archive.read(item))
                if content is not None:
                    out.writestr(item, content)
        with pytest.raises(ValueError, match="--trust-agent"):
            load_agent(broken, ACTIONS)


def test_cli_refuses_the_hostile_zip(tmp_path, capsys):
    pytest.importorskip("aiohttp", reason="octax-gym play needs the play extra")
    from octax_gym.cli import main

    marker = tmp_path / "ran"
    path = tmp_path / "agent.zip"
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("data", json.dumps({"policy_class": _hostile_policy_class(marker)}))
    assert main(["play", "Dodge", "--agent", str(path)]) == 1
    err = capsys.readouterr().err
    assert "octax-gym: error:" in err and "--trust-agent" in err
    assert not marker.exists()
