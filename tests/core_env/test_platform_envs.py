"""SUPER-CHIP and XO-CHIP games as envs (issue 12): one (frames, 64, 128) observation shape
whatever mode the program is in, XO-CHIP's four colours kept apart, 00FD ending the episode,
and the Gymnasium vector env's space and rgb frames to match.

The games are tiny programs written here: each draws known pixels, counts frames in V5 (the
score) and runs 00FD while key 5 (action 1) is held.
"""

from __future__ import annotations

import hashlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from reference import assemble

import octax_core
from octax_core.env.games.spec import GameSpec, register_value


def tiny_game(tmp_path, platform, words, data):
    rom = assemble(*words) + data
    path = tmp_path / f"tiny-{platform}.ch8"
    path.write_bytes(rom)
    spec = GameSpec(id=f"Tiny-{platform}", title="tiny", rom_file=path.name, rom_sha1=hashlib.sha1(rom).hexdigest(),
                    action_keys=(5,), score_fn=lambda s: register_value(s, 5), terminated_fn=lambda s: jnp.bool_(False),
                    category="reaction", description="draws, counts, exits on key 5", platform=platform)
    return spec, path


LOOP = (0x6605, 0x7501, 0xE6A1, 0x00FD)  # V6 = 5; loop: V5 += 1; unless key 5 is up: exit


def xochip_game(tmp_path):
    # hires; (0,0) on both planes, (2,0) on plane 1, (4,0) on plane 2; sprite data at 0x21E
    words = (0x00FF, 0xA21E, 0xF301, 0xD011, 0xF101, 0x6002, 0xD011, 0xF201, 0x6004, 0xD011, *LOOP, 0x1214)
    return tiny_game(tmp_path, "xochip", words, b"\x80\x80")


def schip_game(tmp_path):
    # lores: one pixel at lores (3, 1), a 2x2 block at grid (6, 2); sprite data at 0x212
    words = (0xA212, 0x6003, 0x6101, 0xD011, *LOOP, 0x120A)
    return tiny_game(tmp_path, "schip", words, b"\x80")


@pytest.fixture(scope="module")
def games(tmp_path_factory):
    """Both tiny games, written once for the module: platform -> (spec, ROM path)."""
    folder = tmp_path_factory.mktemp("tiny")
    return {"schip": schip_game(folder), "xochip": xochip_game(folder)}


@pytest.fixture(scope="module")
def tiny(games):
    """make() plus jitted reset and step, built once per (platform, options) for the module. The
    tests all play obs_scale=255 (00FD's end does not depend on the scale), so they share one env
    and one compiled step per platform."""
    built = {}

    def build(platform, **options):
        key = (platform, tuple(sorted(options.items())))
        if key not in built:
            spec, path = games[platform]
            env, params = octax_core.make(spec, rom=path, **options)
            built[key] = env, params, jax.jit(env.reset), jax.jit(env.step)
        return built[key]
    return build


def test_xochip_observation_keeps_four_colours_apart(tiny, games):
    env, params, reset, step = tiny("xochip", obs_scale=255)
    obs, state = reset(jax.random.key(0), params)  # the boot screen: dark
    assert obs.shape == (4, 64, 128) == env.observation_shape and not obs.any()
    obs = step(jax.random.key(1), state, 0, params)[0]
    assert obs.shape == (4, 64, 128) and obs.dtype == jnp.uint8 and env.observation_high == 255
    assert tuple(int(v) for v in obs[-1, 0, [0, 2, 4]]) == (255, 85, 170)
    assert int(np.count_nonzero(np.asarray(obs[-1]))) == 3
    # obs_scale=1 (the default): the same core step, batched by the vector env, whose compiled
    # step the Gymnasium tests below share
    from octax_gym import OctaxVectorEnv

    spec, path = games["xochip"]
    assert octax_core.make(spec, rom=path)[0].observation_high == 3
    envs = OctaxVectorEnv(spec, 2, rom=path)
    obs = envs.reset(seed=0)[0]
    assert obs.shape == (2, 4, 64, 128) and not obs.any()
    obs = envs.step(np.zeros(2, np.int64))[0]
    assert obs.dtype == np.uint8 and tuple(int(v) for v in obs[0, -1, 0, [0, 2, 4]]) == (3, 1, 2)
    assert int(np.count_nonzero(obs[0, -1])) == 3
    envs.close()


def test_schip_lores_pixels_fill_2x2_blocks_of_the_one_shape(tiny):
    env, params, reset, step = tiny("schip", obs_scale=255)
    obs, state = reset(jax.random.key(0), params)
    obs = step(jax.random.key(1), state, 0, params)[0]
    assert obs.shape == (4, 64, 128) and env.observation_high == 255
    assert set(zip(*np.nonzero(np.asarray(obs[-1])))) == {(2, 6), (2, 7), (3, 6), (3, 7)}
    assert int(obs[-1, 2, 6]) == 255


@pytest.mark.parametrize("platform", ["schip", "xochip"])
def test_exit_ends_the_episode_and_the_machine_stands_still(tiny, platform):
    env, params, reset, step = tiny(platform, obs_scale=255)
    obs, state = reset(jax.random.key(0), params)
    obs, state, reward, terminated, truncated, info = step(jax.random.key(1), state, 0, params)
    assert float(reward) > 0 and not bool(terminated)
    obs, state, reward, terminated, truncated, info = step(jax.random.key(2), state, 1, params)
    assert bool(terminated) and bool(state.machine.exited) and bool(state.done)
    again = step(jax.random.key(3), state, 0, params)
    assert float(again[2]) == 0 and bool(again[3])
    assert all(np.array_equal(a, b) for a, b in zip(jax.tree.leaves(state.machine), jax.tree.leaves(again[1].machine)))


# The Gymnasium tests run the XO-CHIP game in 2 envs, as the observation test above does:
# octax_gym compiles one step per (game, config, batch size), so they share it (a palette is
# the renderer's, not the step's).


def test_vector_env_space_and_frames(games):
    from octax_gym import OctaxVectorEnv

    spec, path = games["xochip"]
    envs = OctaxVectorEnv(spec, 2, rom=path, render_mode="rgb_array", render_scale=2, palette="octo")
    assert envs.single_observation_space.shape == (4, 64, 128) and int(envs.single_observation_space.high.max()) == 3
    envs.reset(seed=0)
    obs = envs.step(np.zeros(2, np.int64))[0]
    assert obs.shape == (2, 4, 64, 128) and envs.observation_space.contains(obs)
    frames = envs.render()
    assert len(frames) == 2 and frames[0].shape == (128, 256, 3)
    octo = [(153, 102, 0), (255, 204, 0), (255, 102, 0), (102, 34, 0)]  # off, plane 1, plane 2, both
    assert [tuple(frames[0][0, 2 * x]) for x in (6, 2, 4, 0)] == octo
    envs.close()
    pair = OctaxVectorEnv(spec, 2, rom=path, render_mode="rgb_array", render_scale=1, palette=[(0, 0, 0), (200, 100, 0)])
    pair.reset(seed=0)
    pair.step(np.zeros(2, np.int64))
    assert [tuple(pair.render()[0][0, x]) for x in (6, 2, 4, 0)] == [(0, 0, 0), (200, 100, 0), (100, 50, 0), (50, 25, 0)]
    pair.close()


def test_a_game_brings_its_own_palette(games):
    import dataclasses

    from octax_gym import OctaxVectorEnv

    spec, path = games["xochip"]
    own = ((10, 20, 30), (40, 50, 60), (70, 80, 90), (100, 110, 120))  # off, plane 1, plane 2, both
    spec = dataclasses.replace(spec, palette=own)
    envs = OctaxVectorEnv(spec, 2, rom=path, render_mode="rgb_array", render_scale=1)
    envs.reset(seed=0)
    envs.step(np.zeros(2, np.int64))
    frame = envs.render()[0]
    assert frame.shape == (64, 128, 3) and [tuple(frame[0, x]) for x in (6, 2, 4, 0)] == list(own)
    envs.close()


def test_unknown_platform_in_a_spec(tmp_path):
    with pytest.raises(ValueError, match="unknown platform 'superchip'; valid platforms: 'chip8', 'schip', 'xochip'"):
        tiny_game(tmp_path, "superchip", (0x1200,), b"")


def test_the_env_contract_suite_passes_on_xochip(games):
    """Shapes, dtypes, the four plane codes, determinism, one trace, refused actions, on XO-CHIP.
    One env, so the suite's batch and its env run alone are one compiled step: that env i of a
    batch is the env alone is the env layer's promise, whatever the platform (test_env.py's
    contract suite, three envs), and XO-CHIP's machine keeps it (tests/core_emulator/
    test_platforms.py::test_batches_run_each_machine_as_alone)."""
    spec, path = games["xochip"]
    octax_core.check_env(spec, rom=path, num_envs=1)
