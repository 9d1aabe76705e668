"""Bad input fails early, with the exception type and a message that names the problem.

docs/machine.md, "Bad input": `Rom` refuses an empty program, one over 65024 bytes (XO-CHIP's
64 KiB) and anything that is not bytes, a path or a `Rom`, and `Machine.boot` one larger than its
platform holds (3584 bytes on CHIP-8); `Machine` refuses an unknown profile name (listing the
valid ones) and a non-positive `instructions_per_frame`.
"""

import jax
import numpy as np
import pytest

import octax_core
from octax_core import Machine, Rom

MAX = 3584  # 4096 - 0x200: CHIP-8 and SUPER-CHIP
XOCHIP_MAX = 65024  # 65536 - 0x200


@pytest.fixture
def key():
    return jax.random.key(0)


def loaders(key):
    """Each public way in which a program reaches the machine."""
    return {
        "Rom": Rom,
        "Rom.load": Rom.load,
        "Machine.boot": lambda data: Machine("chip8").boot(data, key),
    }


@pytest.mark.parametrize("way", ["Rom", "Rom.load", "Machine.boot"])
def test_empty_rom(way, key):
    with pytest.raises(ValueError, match=r"(?i)empty"):
        loaders(key)[way](b"")


@pytest.mark.parametrize("size", [MAX + 1, 4096])
def test_rom_too_large_for_chip8(key, size):
    with pytest.raises(ValueError, match=rf"{size}.*\b{MAX}\b"):
        loaders(key)["Machine.boot"](bytes(size))


@pytest.mark.parametrize("way", ["Rom", "Rom.load", "Machine.boot"])
@pytest.mark.parametrize("size", [XOCHIP_MAX + 1, 70000])
def test_rom_too_large_for_any_platform(way, key, size):
    with pytest.raises(ValueError, match=rf"{size}.*\b{MAX}\b.*\b{XOCHIP_MAX}\b"):
        loaders(key)[way](bytes(size))


@pytest.mark.parametrize("way", ["Rom", "Rom.load", "Machine.boot"])
def test_largest_and_smallest_roms_load(way, key):
    for data in (bytes([0x12]), bytes(MAX)):
        loaders(key)[way](data)


@pytest.mark.parametrize("way", ["Rom", "Rom.load", "Machine.boot"])
@pytest.mark.parametrize("bad", [42, [0x12, 0x00], None, 3.5], ids=["int", "list", "None", "float"])
def test_not_bytes(way, key, bad):
    with pytest.raises(TypeError, match=type(bad).__name__):
        loaders(key)[way](bad)


def test_rom_from_a_str_is_a_path_not_data():
    """A str names a file; it is never taken as program text."""
    with pytest.raises(TypeError):
        Rom("\x12\x00")


@pytest.mark.parametrize("way", ["Rom.load", "Machine.boot"])
@pytest.mark.parametrize("as_str", [True, False], ids=["str", "Path"])
def test_missing_file(way, key, tmp_path, as_str):
    path = tmp_path / "no-such-rom.ch8"
    with pytest.raises(FileNotFoundError, match="no-such-rom.ch8"):
        loaders(key)[way](str(path) if as_str else path)


@pytest.mark.parametrize("way", ["Rom.load", "Machine.boot"])
def test_empty_and_oversized_files(way, key, tmp_path):
    empty, big = tmp_path / "empty.ch8", tmp_path / "big.ch8"
    empty.write_bytes(b"")
    size = MAX + 1 if way == "Machine.boot" else XOCHIP_MAX + 1  # too large for CHIP-8 / for any platform
    big.write_bytes(bytes(size))
    with pytest.raises(ValueError, match=r"(?i)empty"):
        loaders(key)[way](empty)
    with pytest.raises(ValueError, match=rf"{size}.*\b{MAX}\b"):
        loaders(key)[way](big)


def test_a_directory_is_not_a_rom(key, tmp_path):
    with pytest.raises((FileNotFoundError, IsADirectoryError, ValueError)):
        Machine("chip8").boot(tmp_path, key)


@pytest.mark.parametrize("name", ["CHIP8", "chip-8", "xo-chip", "", "superchip"])
def test_unknown_profile_lists_valid_ones(name):
    with pytest.raises(ValueError, match=r"(?s)(?=.*'chip8')(?=.*'schip')(?=.*'xochip')") as info:
        Machine(quirks=name)
    assert repr(name) in str(info.value)


def test_quirks_of_the_wrong_type():
    with pytest.raises(TypeError, match="int"):
        Machine(quirks=1)


def test_profiles_are_the_documented_ones():
    assert set(octax_core.QUIRK_PROFILES) == {"chip8", "schip", "xochip"}


@pytest.mark.parametrize("ipf", [0, -1, -11])
def test_non_positive_instructions_per_frame(ipf):
    with pytest.raises(ValueError, match=rf"instructions_per_frame.*{ipf}"):
        Machine("chip8", instructions_per_frame=ipf)


@pytest.mark.parametrize("ipf", [1.5, "11", True])
def test_instructions_per_frame_must_be_an_int(ipf):
    with pytest.raises((TypeError, ValueError), match="instructions_per_frame"):
        Machine("chip8", instructions_per_frame=ipf)


def test_quirks_need_all_six_fields():
    with pytest.raises(TypeError):
        octax_core.Quirks(vf_reset=True)


# --- keys and frames given to run_frames ---------------------------------------------------------

PROGRAM = bytes([0x12, 0x00])  # 1200: jump to self


@pytest.fixture(scope="module")
def booted():
    machine = octax_core.Machine("chip8")
    return machine, machine.boot(PROGRAM, jax.random.key(0))


@pytest.mark.parametrize("mask", [-1, 0x10000, 1 << 20])
def test_key_mask_out_of_range(booted, mask):
    machine, state = booted
    with pytest.raises(ValueError, match=r"key mask must be in 0\.\.0xFFFF"):
        machine.run_frames(state, mask, 1)


@pytest.mark.parametrize("shape", [(15,), (17,), (4, 4)])
def test_key_array_of_the_wrong_length(booted, shape):
    machine, state = booted
    with pytest.raises(ValueError, match="16 entries"):
        machine.run_frames(state, np.zeros(shape, bool), 1)


def test_key_array_of_the_wrong_dtype(booted):
    machine, state = booted
    with pytest.raises(TypeError, match="bool\\[16\\] array or an integer bit mask"):
        machine.run_frames(state, np.zeros(16, np.float32), 1)


@pytest.mark.parametrize("frames, error, message", [(-1, ValueError, ">= 0"), (1.5, TypeError, "Python int")])
def test_bad_frame_counts(booted, frames, error, message):
    machine, state = booted
    with pytest.raises(error, match=message):
        machine.run_frames(state, 0, frames)


def test_render_text_refuses_a_batch():
    machine = octax_core.Machine("chip8")
    batch = jax.vmap(lambda k: machine.boot(PROGRAM, k))(jax.random.split(jax.random.key(0), 2))
    with pytest.raises(ValueError, match="one machine"):
        octax_core.render_text(batch)
