"""Batched equals single: `vmap` over 8 machines gives exactly the 8 single-machine runs.

Each of the 8 machines boots with its own key (so CXNN differs) and gets its own keys, which
change every few calls. The batch takes its keys as bool[8, 16], the single runs as integer
masks, so both key forms are covered too.
"""

import random
import zlib
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from reference import first_difference
from shared_data import TEST_SUITE_DIR, octax_rom_folder

import octax_core

OCTAX_ROMS = octax_rom_folder() or Path("no-octax-roms")  # the octax suite, from ../shared or the ROM store
CASES = [
    pytest.param(OCTAX_ROMS / "Brix [Andreas Gustafsson, 1990].ch8", "chip8", id="Brix"),
    pytest.param(OCTAX_ROMS / "Tetris [Fran Dachille, 1991].ch8", "schip", id="Tetris"),
    pytest.param(TEST_SUITE_DIR / "6-keypad.ch8", "chip8", id="6-keypad", marks=pytest.mark.shared),
]
BATCH = 8
FRAMES_PER_CALL = 10
CALLS = 20


def unbatch(snap, index):
    return {name: value[index] for name, value in snap.items()}


def key_masks(seed):
    """CALLS rows of BATCH masks; each env holds one choice for 1..4 calls."""
    rng = random.Random(seed)
    columns = []
    for _ in range(BATCH):
        column = []
        while len(column) < CALLS:
            mask = rng.choice([0, 0, 1 << rng.randrange(16), rng.randrange(1 << 16)])
            column += [mask] * rng.randint(1, 4)
        columns.append(column[:CALLS])
    return [[columns[env][call] for env in range(BATCH)] for call in range(CALLS)]


def as_bools(masks):
    return jnp.asarray([[bool((mask >> k) & 1) for k in range(16)] for mask in masks])


@pytest.mark.parametrize("rom_path, profile", CASES)
def test_batched_equals_single(rom_path, profile, jit_run_frames, jit_batch_run_frames):
    rom = rom_path.read_bytes()
    machine = octax_core.Machine(quirks=profile, instructions_per_frame=11)
    boot_keys = jax.random.split(jax.random.key(7), BATCH)
    singles = [machine.boot(rom, boot_keys[env]) for env in range(BATCH)]
    batch = jax.tree.map(lambda *leaves: jnp.stack(leaves), *singles)
    rngs = octax_core.snapshot(batch)["rng"]
    assert len(set(rngs.tolist())) == BATCH, "boot keys should give different rng states"

    run_single = jit_run_frames(machine)  # one frame a call: test_differential.py's program, one compile for both
    run_batch = jit_batch_run_frames(machine, FRAMES_PER_CALL)  # the folder's batched runner (conftest.py)
    for call, masks in enumerate(key_masks(zlib.crc32(rom_path.name.encode()))):
        batch = run_batch(batch, as_bools(masks))
        for _ in range(FRAMES_PER_CALL):
            singles = [run_single(state, mask, 1) for state, mask in zip(singles, masks)]
        batch_snap = octax_core.snapshot(batch)
        for env, state in enumerate(singles):
            difference = first_difference(octax_core.snapshot(state), unbatch(batch_snap, env))
            assert difference is None, (
                f"{rom_path.name} [{profile}] env {env}, after frame {(call + 1) * FRAMES_PER_CALL}: "
                f"{difference}")
    assert np.any(batch_snap["screen"]), "the ROM should have drawn something"
    distinct = {tuple(np.concatenate([batch_snap[name][env].ravel().astype(np.int64)
                                      for name in ("V", "pc", "screen")])) for env in range(BATCH)}
    assert len(distinct) > 1, "the 8 machines should have diverged, or the test shows little"


def test_vmapped_boot_equals_single_boots():
    rom_path, profile = CASES[0].values
    rom = rom_path.read_bytes()
    machine = octax_core.Machine(quirks=profile)
    boot_keys = jax.random.split(jax.random.key(3), BATCH)
    batch_snap = octax_core.snapshot(jax.vmap(lambda key: machine.boot(rom, key))(boot_keys))
    for env in range(BATCH):
        single = octax_core.snapshot(machine.boot(rom, boot_keys[env]))
        assert first_difference(single, unbatch(batch_snap, env)) is None, f"env {env}"

