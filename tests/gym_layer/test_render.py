"""rgb_array rendering: OpenCV nearest-neighbour upscale of the 64x32 screen, palettes, tuples."""

from __future__ import annotations

import jax
import numpy as np
import pytest

import octax_core
from counter_game import COUNTER
from octax_gym import OctaxEnv, OctaxVectorEnv
from octax_gym.envs import render


def screens_of(envs) -> np.ndarray:
    return np.asarray(octax_core.emulator.state.unpack_screen(envs.state.machine.screen))


def test_vector_render_is_a_tuple_of_upscaled_frames(counter_rom):
    envs = OctaxVectorEnv(COUNTER, 3, rom=counter_rom, render_mode="rgb_array", render_scale=4, palette="green")
    envs.reset(seed=0)
    envs.step(np.array([0, 1, 2]))
    frames = envs.render()
    assert isinstance(frames, tuple) and len(frames) == 3
    screens = screens_of(envs)
    off, on = render.PALETTES["green"][:2]  # (XO-CHIP's two more colours follow)
    for frame, screen in zip(frames, screens):
        assert frame.shape == (128, 256, 3) and frame.dtype == np.uint8
        # Every 4x4 block is one pixel's colour: lit pixels `on`, the rest `off`.
        blocks = frame.reshape(32, 4, 64, 4, 3)
        assert (blocks == blocks[:, :1, :, :1]).all()
        expected = np.where(screen[..., None], np.array(on, np.uint8), np.array(off, np.uint8))
        np.testing.assert_array_equal(blocks[:, 0, :, 0], expected)
    assert screens.any(axis=(1, 2)).all() and not (screens[1] == screens[2]).all()  # digits at y=4, y=8


def test_the_observation_last_frame_is_the_rendered_screen(counter_rom):
    env = OctaxEnv(COUNTER, rom=counter_rom, render_mode="rgb_array", render_scale=1)
    env.reset(seed=3)
    obs, *_ = env.step(1)
    frame = env.render()
    assert frame.shape == (32, 64, 3)
    np.testing.assert_array_equal(frame[..., 0] == 255, obs[-1] == 1)


def test_custom_palette_pair():
    colours = render.resolve_palette([(1, 2, 3), (250, 251, 252)])
    pixels = np.zeros((32, 64), bool)
    pixels[0, 63] = True
    frame = render.to_rgb(pixels, 2, colours)
    assert tuple(frame[0, 127]) == (250, 251, 252) and tuple(frame[0, 0]) == (1, 2, 3)
    assert tuple(frame[2, 127]) == (1, 2, 3)


def test_the_one_unpacker_gives_numpy_on_the_host_and_the_same_pixels_under_jit():
    words = np.random.default_rng(0).integers(0, 2**32, size=(5, 32, 2), dtype=np.uint64).astype(np.uint32)
    on_host = octax_core.emulator.state.unpack_screen(words)
    assert isinstance(on_host, np.ndarray) and on_host.dtype == np.bool_ and on_host.shape == (5, 32, 64)
    jitted = jax.jit(octax_core.emulator.state.unpack_screen)(words)
    np.testing.assert_array_equal(on_host, np.asarray(jitted))
    # Pixel x of row y is bit 31 - x % 32 of word x // 32, written out the slow way.
    slow = [[[bool(words[i, y, x // 32] >> (31 - x % 32) & 1) for x in range(64)] for y in range(32)] for i in range(5)]
    np.testing.assert_array_equal(on_host, np.array(slow))


def test_tile_makes_an_even_sided_grid():
    frames = [np.full((5, 7, 3), i * 50, np.uint8) for i in range(3)]
    grid = render.tile(frames, gap=1)
    assert grid.shape == (12, 16, 3)  # 2 x 2 cells of 5 x 7, 1-pixel gaps, rounded up to even
    assert (grid[:5, :7] == 0).all() and (grid[:5, 8:15] == 50).all() and (grid[6:11, :7] == 100).all()
    assert (grid[6:11, 8:15] == 64).all()  # the empty cell is the grey background
    with pytest.raises(ValueError, match="at least one frame"):
        render.tile([])
