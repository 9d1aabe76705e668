"""`octax-gym play`'s agents (the JAX examples' params, SB3 zips), recording without a browser,
and the command line (a real server process: it prints its address, serves the page, stops on
Ctrl-C)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from octax_gym.play.agents import load_agent
from octax_gym.play.session import Session

from host_params import fill_like

REPO = Path(__file__).resolve().parents[2]
GAME = "Dodge"


@pytest.fixture(scope="module")
def networks():
    pytest.importorskip("flax", reason="the trainer's networks need flax (the train extra)")
    from octax_gym.train import networks
    return networks


# Three screens of 4 random planes, drawn on the host: the tests' one batch of observations.
OBS = np.random.default_rng(1).integers(0, 2, (3, 4, 32, 64), dtype=np.uint8)


@pytest.fixture(scope="module")
def initialized(networks):
    """(network, params) of a trainer's network kind ("ppo" or "pqn") and width, the params drawn
    on the host in its init's shapes (tests/host_params.py). Which weights does not matter here (a
    file's params must play as the network plays those params), and no init program is compiled."""
    import jax

    def get(kind: str, width: int):
        network = networks.ActorCritic(width) if kind == "ppo" else networks.QNetwork(width)
        return network, fill_like(jax.eval_shape(network.init, jax.random.key(0), OBS), seed=width)
    return get


@pytest.mark.parametrize("kind", ["ppo", "pqn"])
@pytest.mark.parametrize("width", [3, 17], ids=["examples-file", "trainer-file"])
def test_jax_params_play_as_the_trainers_network(initialized, kind, width, tmp_path):
    import flax.serialization

    from octax_gym.jax_policy import action_scores

    network, params = initialized(kind, width)
    obs = OBS
    path = tmp_path / "params.msgpack"
    path.write_bytes(flax.serialization.to_bytes(params))
    ours = action_scores(flax.serialization.msgpack_restore(path.read_bytes()), obs)
    theirs = network.apply(params, obs)[0] if kind == "ppo" else network.apply(params, obs)
    np.testing.assert_array_equal(np.asarray(ours), np.asarray(theirs))
    agent = load_agent(path, 3)  # a game of 3 actions: a 17-wide agent picks among its first 3
    assert [agent(np.asarray(o)) for o in obs] == list(np.asarray(theirs)[:, :3].argmax(-1))
    # A one-player agent in a two-player seat gets the screens without the player plane.
    assert agent(np.concatenate([np.asarray(obs[0]), np.ones((1, 32, 64), np.uint8)])) == agent(np.asarray(obs[0]))
    with pytest.raises(ValueError, match=f"plays {width} actions"):
        load_agent(path, 5 if width == 3 else 18)


def test_float16_params_play_as_their_float32_originals(initialized, tmp_path):
    import flax.serialization
    import jax

    network, params = initialized("ppo", 17)  # a trainer's file, as the params test saves it
    obs = OBS
    half = tmp_path / "half.msgpack"
    half.write_bytes(flax.serialization.to_bytes(jax.tree.map(lambda x: x.astype(np.float16), params)))
    agent = load_agent(half, 4)
    expected = np.asarray(network.apply(jax.tree.map(lambda x: x.astype(np.float16).astype(np.float32), params),
                                        obs)[0])[:, :4].argmax(-1)
    assert len(set(expected)) > 1  # the rows' choices differ: a loader ignoring the screen would fail
    assert [agent(np.asarray(o)) for o in obs] == list(expected)


def test_bad_agent_files(tmp_path):
    with pytest.raises(FileNotFoundError):
        load_agent(tmp_path / "missing.msgpack", 3)
    junk = tmp_path / "junk.msgpack"
    junk.write_bytes(b"\x00not msgpack at all")
    with pytest.raises((ValueError, ImportError)):
        load_agent(junk, 3)


def test_sb3_zip_plays(tmp_path):
    pytest.importorskip("stable_baselines3", reason="SB3 zips need the sb3 extra")
    from stable_baselines3 import PPO

    from octax_gym.sb3 import make_sb3_vec_env, ppo_kwargs

    venv = make_sb3_vec_env(GAME, 2)
    model = PPO("CnnPolicy", venv, **{**ppo_kwargs(2, 1), "n_steps": 8, "batch_size": 16}, seed=0)
    model.save(tmp_path / "agent.zip")
    agent = load_agent(tmp_path / "agent.zip", venv.action_space.n)  # rebuilt from data, not unpickled
    obs = venv.reset()
    assert agent(obs[0]) == int(model.predict(obs[:1], deterministic=True)[0][0])
    # More cases, and zips that run code when SB3 loads them: test_agent_files_safety.py
    session = Session(GAME, agent=agent)
    assert session.players == ["agent"]
    actions = {session.step()["actions"][0] for _ in range(10)}
    assert actions <= {0, 1, 2}
    session.close()
    venv.close()


def test_recorded_human_episodes_replay(tmp_path, monkeypatch):
    pytest.importorskip("minari", reason="recording needs the datasets extra")
    from octax_gym.datasets import episode_seed
    from octax_gym.play.record import Recorder
    from octax_gym.envs.vector import OctaxVectorEnv

    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path))
    probe = OctaxVectorEnv(GAME, 1)
    recorder = Recorder(GAME, "test/Dodge-human-v0", observation_space=probe.single_observation_space,
                        num_actions=3, recorder="pytest")
    session = Session(GAME, seed=40, recorder=recorder, max_episode_steps=30)
    left, right = session.seat_keys[0]
    for t in range(40):                         # episode 0 runs to its truncation at 30 steps
        session.key(left if t % 10 < 5 else right, True)
        session.step()
        session.key(left, False)
        session.key(right, False)
    assert session.done
    session.reset()
    for _ in range(7):                          # episode 1: reset after 7 steps, stored cut
        session.key(right, True)
        session.step()
    session.reset()
    session.set_player(0, "random")             # episode 2: not the human's, left out
    for _ in range(5):
        session.step()
    session.close()
    dataset = recorder.close()
    assert dataset.total_episodes == 2 and dataset.total_steps == 37
    env = dataset.recover_environment()
    for episode, seed, length in zip(dataset.iterate_episodes(), (40, 41), (30, 7)):
        assert episode_seed(dataset, episode.id) == seed and len(episode.actions) == length
        assert episode.truncations[-1]
        obs, _ = env.reset(seed=seed)
        assert np.array_equal(obs, episode.observations[0])
        for t, action in enumerate(episode.actions):
            obs, reward, *_ = env.step(int(action))
            assert np.array_equal(obs, episode.observations[t + 1]) and reward == episode.rewards[t]
    assert set(episode.infos) == {"score", "lives", "episode_step"}
    _, info = probe.reset(seed=0)
    for name in ("score", "lives", "episode_step"):  # the env's own dtypes, as collect_dataset stores them
        assert episode.infos[name].dtype == info[name].dtype


def test_cli_parser_and_errors(capsys):
    from octax_gym.cli import main

    with pytest.raises(SystemExit):
        main(["play", "--help"])
    out = capsys.readouterr().out
    assert "--agent" in out and "--record" in out and "--host" in out and "--trust-agent" in out
    assert main(["play", "NoSuchGame"]) == 1
    assert main(["play", "Duel", "--record", "x/Duel-v0"]) == 1
    assert "two-player" in capsys.readouterr().err
    assert main(["play", GAME, "--players", "human,human"]) == 1


def test_cli_serves_and_stops_on_ctrl_c(tmp_path):
    pytest.importorskip("aiohttp", reason="octax-gym play needs the play extra")
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    # stderr (the server's log) goes to a file: a pipe nobody reads could fill and block the server
    log = open(tmp_path / "stderr.log", "w+")
    out = open(tmp_path / "stdout.log", "w+")  # a file too: nothing the server prints can block it
    process = subprocess.Popen([sys.executable, "-m", "octax_gym", "play", GAME, "--seed", "3"], cwd=REPO, env=env,
                               stdout=out, stderr=log, text=True)
    try:
        line = ""
        deadline = time.monotonic() + 120
        while "http://" not in line and time.monotonic() < deadline and process.poll() is None:
            time.sleep(0.2)
            line = next((l for l in (tmp_path / "stdout.log").read_text().splitlines() if "http://" in l), "")
        assert "http://127.0.0.1:" in line, (tmp_path / "stderr.log").read_text()
        url = line[line.index("http://"):].split()[0]
        with urllib.request.urlopen(url, timeout=10) as response:
            assert response.status == 200 and b"play.js" in response.read()
        process.send_signal(signal.SIGINT)
        # a loaded 2-core machine may still be compiling the env's step when the signal comes
        assert process.wait(timeout=120) == 0, (tmp_path / "stderr.log").read_text()
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
        log.close()
        out.close()
