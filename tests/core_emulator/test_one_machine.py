"""One machine for three platforms: the gated work (`gate.when_any`), the two display surfaces,
and a CHIP-8 program run alike by the chip8, schip and xochip machines."""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import octax_core
from octax_core.emulator import cpu, frame
from octax_core.emulator.gate import any_of_batch, when_any
from octax_core.emulator.ops import display
from octax_core.emulator.state import shown


def _add_where(operands, inputs):
    """A gated function: adds `inputs[1]` where `inputs[0]`, else leaves the operand as it is."""
    on, amount = inputs
    return jnp.where(on, operands + amount, operands)


@pytest.fixture(scope="module")
def gated():
    return jax.jit(jax.vmap(lambda pred, x, amount: when_any(pred, _add_where, x, (pred, amount))))


def test_when_any_runs_the_work_for_the_machines_that_need_it(gated):
    x = jnp.arange(6, dtype=jnp.int32) * 10
    pred = jnp.array([False, True, False, False, True, False])
    out = gated(pred, x, jnp.full(6, 7, jnp.int32))
    np.testing.assert_array_equal(out, np.where(pred, x + 7, x))
    none = gated(jnp.zeros(6, bool), x, jnp.full(6, 7, jnp.int32))
    np.testing.assert_array_equal(none, x)


def test_when_any_skips_the_work_when_no_machine_needs_it():
    """With no machine asking, `fn` does not run at all: a work that would change every machine
    (breaking the contract on purpose) shows whether it ran."""
    def everyone(operands, inputs):
        return operands + 1

    run = jax.jit(jax.vmap(lambda pred, x: when_any(pred, everyone, x)))
    x = jnp.zeros(4, jnp.int32)
    np.testing.assert_array_equal(run(jnp.zeros(4, bool), x), [0, 0, 0, 0])
    np.testing.assert_array_equal(run(jnp.array([False, True, False, False]), x), [1, 1, 1, 1])


def test_when_any_unbatched_and_nested():
    one = jax.jit(lambda pred, x: when_any(pred, _add_where, x, (pred, jnp.int32(5))))
    assert int(one(True, jnp.int32(1))) == 6 and int(one(False, jnp.int32(1))) == 1
    nested = jax.jit(jax.vmap(jax.vmap(lambda pred, x: when_any(pred, _add_where, x, (pred, jnp.int32(5))))))
    pred = jnp.array([[True, False], [False, False]])
    np.testing.assert_array_equal(nested(pred, jnp.ones((2, 2), jnp.int32)), [[6, 1], [1, 1]])
    # an unbatched predicate over a batch: the whole batch, or nobody
    shared = jax.jit(jax.vmap(lambda x, pred: when_any(pred, _add_where, x, (pred, jnp.int32(5))), in_axes=(0, None)))
    np.testing.assert_array_equal(shared(jnp.ones(3, jnp.int32), True), [6, 6, 6])


def test_any_of_batch_reduces_every_predicate_at_once():
    """Each predicate's answer for the whole batch, from one reduction; a predicate the batch
    shares is its own answer; one machine alone gets its predicates back. A `when_any` fed the
    answer runs its work for the whole batch exactly when some machine needs it."""
    a = jnp.array([False, True, False, False])
    b = jnp.zeros(4, bool)
    batched = jax.jit(jax.vmap(lambda p, q, r: any_of_batch(p, q, r), in_axes=(0, 0, None), out_axes=None))
    assert [bool(x) for x in batched(a, b, True)] == [True, False, True]
    assert [bool(x) for x in jax.jit(any_of_batch)(True, False)] == [True, False]

    def gated(pred, x):
        (anyone,) = any_of_batch(pred)
        return when_any(anyone, _add_where, x, (pred, jnp.int32(7)))

    run = jax.jit(jax.vmap(gated))
    x = jnp.arange(4, dtype=jnp.int32)
    np.testing.assert_array_equal(run(a, x), np.where(a, x + 7, x))
    np.testing.assert_array_equal(run(b, x), x)


def test_upscale_doubles_every_pixel():
    lores = np.zeros((32, 2), np.uint32)
    lores[3, 0] = 1 << 31  # pixel (0, 3)
    lores[31, 1] = 1  # pixel (63, 31)
    grid = np.asarray(octax_core.emulator.state.unpack_screen(display.upscale(lores)))
    assert grid.shape == (64, 128)
    assert set(zip(*np.nonzero(grid))) == {(6, 0), (6, 1), (7, 0), (7, 1), (62, 126), (62, 127), (63, 126), (63, 127)}
    np.testing.assert_array_equal(np.asarray(display.upscale(jnp.asarray(lores))), display.upscale(lores))


@pytest.mark.parametrize("clipping", [True, False])
def test_a_sprite_on_both_surfaces_is_the_same_picture(clipping):
    """The 64x32 surface with its pixels doubled is the 128x64 grid drawn with doubled sprite
    rows at doubled coordinates: the two surfaces agree, edges and wrap included."""
    rng = np.random.default_rng(0)
    for _ in range(20):
        patterns = jnp.asarray(rng.integers(0, 1 << 16, 16, dtype=np.uint32) << 16)
        x, y, height = (jnp.int32(v) for v in (rng.integers(0, 64), rng.integers(0, 32), rng.integers(0, 17)))
        lores = display.sprite_mask(patterns, x, y, height, display.LORES, clipping)
        doubled_rows = jnp.repeat(display.double_bits(patterns >> 16), 2)  # 32 grid rows of 32 bits
        tiled = jnp.concatenate([doubled_rows, jnp.zeros(32, jnp.uint32)])
        words = display.place(tiled, 2 * x, 4, clipping)  # (64, 4): grid rows of the sprite's frame
        rows = np.asarray(words)
        grid = np.zeros((64, 4), np.uint32)
        for r in range(2 * int(height)):
            target = 2 * int(y) + r
            if target >= 64 and clipping:
                continue
            grid[target % 64] |= rows[r]
        np.testing.assert_array_equal(display.upscale(np.asarray(lores)), grid)


PONG = "Pong (1 player).ch8"


def pong_machine(platform: str) -> octax_core.Machine:
    return octax_core.Machine(platform, quirks="chip8", instructions_per_frame=11)


@functools.lru_cache(maxsize=None)
def pong_program(machine: octax_core.Machine):
    """8 machines, 300 recorded frames, with the platform's compiler options (exact: see
    test_compiler_options.py): the program the Pong test runs and the copy test reads, one
    compile for both."""
    return jax.jit(jax.vmap(lambda s, k: machine.run_frames(s, k, 300, record_screens=True)),
                   compiler_options=machine.compiler_options)


@pytest.fixture(scope="module")
def pong_runs(octax_rom_dir):
    """Pong, 11 instructions a frame, the chip8 quirks, 8 machines with random keys, 300 frames,
    on each platform: (state, recorded pictures) by platform name."""
    rom = (octax_rom_dir / PONG).read_bytes()
    keys = jax.random.randint(jax.random.key(1), (8,), 0, 1 << 16).astype(jnp.uint32) & 0x1012
    out = {}
    for platform in ("chip8", "schip", "xochip"):
        machine = pong_machine(platform)
        boot = jax.vmap(lambda k: machine.boot(rom, k))(jax.random.split(jax.random.key(0), 8))
        out[platform] = pong_program(machine)(boot, keys)
    return out


def test_one_chip8_program_runs_alike_on_every_platform(pong_runs):
    """A CHIP-8 program that uses no later opcode plays the same on the later machines: the same
    registers, RAM and timers, and the same picture, doubled, in every recorded frame."""
    chip8_state, chip8_screens = pong_runs["chip8"]
    assert np.asarray(chip8_screens).any()
    for platform in ("schip", "xochip"):
        state, screens = pong_runs[platform]
        for field in ("V", "I", "pc", "sp", "stack", "delay_timer", "sound_timer", "rng", "key_wait"):
            np.testing.assert_array_equal(getattr(state, field), getattr(chip8_state, field), err_msg=field)
        ram = np.array(octax_core.emulator.state.ram_view(np.asarray(state.memory))[..., :4096])
        chip8_ram = octax_core.emulator.state.ram_view(np.asarray(chip8_state.memory))
        big_font = slice(0xA0, 0xA0 + 160)  # the later platforms' big digits, where CHIP-8 has zeros
        ram[..., big_font] = 0
        np.testing.assert_array_equal(ram, chip8_ram)
        expected = display.upscale(np.asarray(chip8_screens))  # (8, 300, 64, 4)
        np.testing.assert_array_equal(np.asarray(screens)[:, :, 0], expected, err_msg=platform)
        if platform == "xochip":
            assert not np.asarray(screens)[:, :, 1].any()  # plane 2 never drawn
        assert not np.asarray(state.extension.grid).any() and not np.asarray(state.extension.hires).any()


def _xochip_drawing(planes: int, hires: bool) -> bytes:
    """An XO-CHIP program: select `planes`, draw a 5-row sprite (two, one per plane, when both are
    selected) three times at (5, 3), keeping VF after the second draw in V2 and after the third in
    V3, then spin."""
    words = [0x00FF] if hires else []
    words += [0xF001 | planes << 8, 0xA220, 0x6005, 0x6103, 0xD015, 0xD015, 0x82F0, 0xD015, 0x83F0]
    code = b"".join(w.to_bytes(2, "big") for w in words)
    code += (0x1200 + len(code)).to_bytes(2, "big")  # jump to self
    sprite = bytes([0xF0, 0x90, 0x90, 0x90, 0xF0]) + bytes([0xFF, 0x81, 0x81, 0x81, 0xFF])
    return code.ljust(0x20, b"\0") + sprite


def test_plane_2_is_drawn_where_a_machine_asks_in_any_batch(jit_run_frames, jit_batch_run_frames):
    """XO-CHIP's plane 2 on the 64x32 screen is gated work (`cpu._draw_second_plane`): in a batch
    where machines draw on plane 1, plane 2, both, none, or in hires, each machine's screen, grid
    and collisions are its own run alone, and a batch where no machine asks leaves plane 2 dark.
    (The machine, batch size and frame count are test_platforms.py's batch test's: one compile
    of each program for both.)"""
    machine = octax_core.Machine("xochip", instructions_per_frame=30)
    cases = [(1, False), (2, False), (3, False), (0, False), (3, True), (2, True)]
    states = [machine.boot(_xochip_drawing(planes, hires), jax.random.key(i)) for i, (planes, hires) in enumerate(cases)]
    alone = [jit_run_frames(machine)(state, 0, 1) for state in states]  # one compile for the six
    batch = jax.tree.map(lambda *leaves: jnp.stack(leaves), *states)
    no_keys = jnp.zeros(len(cases), jnp.uint32)

    def run(batch):
        return jit_batch_run_frames(machine, 1)(batch, no_keys)

    together = run(batch)
    for m, ((planes, hires), one) in enumerate(zip(cases, alone)):
        for path, leaf, expected in zip(jax.tree_util.tree_flatten_with_path(one)[0], jax.tree.leaves(together),
                                        jax.tree.leaves(one)):
            if jnp.issubdtype(leaf.dtype, jax.dtypes.prng_key):
                leaf, expected = jax.random.key_data(leaf), jax.random.key_data(expected)
            np.testing.assert_array_equal(np.asarray(leaf)[m], np.asarray(expected), err_msg=f"{m} {path[0]}")
        V = np.asarray(one.V)
        assert (V[2], V[3]) == ((1, 0) if planes else (0, 0)), (planes, hires)  # the second draw erased
        surface = np.asarray(one.extension.grid if hires else one.screen)
        assert [bool(surface[p].any()) for p in range(2)] == [bool(planes & 1), bool(planes & 2)]
    plane_1_only = jax.tree.map(lambda leaf: leaf[np.array([0, 3, 0, 3, 0, 3])], batch)  # the batch's shape: no new compile
    assert not np.asarray(run(plane_1_only).screen)[:, 1].any()


def test_the_frame_loop_is_the_only_loop(monkeypatch):
    """Every path of `Machine.run_frames` goes through `frame.frame_runner` (skipping or not,
    recording or not); the executor is `cpu.execute` for every platform. (The runners handed out
    here are stand-ins that return the state as it is: what is counted is who asks for one, and
    tracing 18 real frame loops proved nothing more and took seconds.)"""
    asked = []

    def runner(*args, **kwargs):
        asked.append((args, tuple(sorted(kwargs.items()))))
        return lambda state, keys, halted, profile: (state, jnp.zeros((args[3],) + shown(state).shape, jnp.uint32))

    monkeypatch.setattr(frame, "frame_runner", runner)
    for platform in ("chip8", "schip", "xochip"):
        for ipf, skip in ((11, True), (40, True), (40, False)):
            machine = octax_core.Machine(platform, instructions_per_frame=ipf, skip_idle=skip)
            state = machine.boot(b"\x12\x00", jax.random.key(0))
            jax.eval_shape(lambda s: machine.run_frames(s, 0, 2, record_screens=True), state)
            jax.eval_shape(lambda s: machine.run_frames(s, 0, jnp.int32(2)), state)
    assert len(asked) == len(set(asked)) == 3 * 3 * 2  # per platform and config: the recording loop and the one-frame loop
    assert not hasattr(octax_core.emulator, "cpu_extended")
    assert cpu.handlers(octax_core.PLATFORMS["chip8"]).keys() < cpu.handlers(octax_core.PLATFORMS["xochip"]).keys()


def test_shown_is_the_picture_of_the_mode(jit_run_frames):
    # (the one-frame program of test_platforms.py's exit tests, called alike: one compile for all)
    machine = octax_core.Machine("schip", instructions_per_frame=5)
    # hires; draw the 8x1 sprite 0xFF at (0, 0); loop
    program = bytes([0x00, 0xFF, 0xA2, 0x08, 0xD0, 0x01, 0x12, 0x06, 0xFF])
    state = jit_run_frames(machine)(machine.boot(program, jax.random.key(0)), jnp.uint32(0), 1, halted=jnp.bool_(False))
    assert bool(state.extension.hires) and not np.asarray(state.screen).any()
    np.testing.assert_array_equal(np.asarray(shown(state)), np.asarray(state.extension.grid))
    assert octax_core.render_text(state).splitlines()[0][:9] == "########."


def test_off_the_looped_platforms_the_work_always_runs(monkeypatch):
    """Where the gate does not loop (a GPU: `LOOPED_PLATFORMS` leaves it out), `fn` runs for the
    whole batch even when no machine asks (shown by a work that breaks the contract on purpose);
    with the contract kept, the result is the looped one."""
    from octax_core.emulator import gate

    monkeypatch.setattr(gate, "LOOPED_PLATFORMS", ())
    run = jax.jit(jax.vmap(lambda pred, x: when_any(pred, lambda o, i: o + 1, x)))
    np.testing.assert_array_equal(run(jnp.zeros(4, bool), jnp.zeros(4, jnp.int32)), [1, 1, 1, 1])
    one = jax.jit(lambda pred, x: when_any(pred, _add_where, x, (pred, jnp.int32(5))))
    assert int(one(True, jnp.int32(1))) == 6 and int(one(False, jnp.int32(1))) == 1
    kept = jax.jit(jax.vmap(lambda pred, x, amount: when_any(pred, _add_where, x, (pred, amount))))
    pred = jnp.array([False, True, False, False, True, False])
    x = jnp.arange(6, dtype=jnp.int32)
    np.testing.assert_array_equal(kept(pred, x, jnp.full(6, 7, jnp.int32)), np.where(pred, x + 7, x))


def test_where_looped_picks_by_the_platform_the_program_is_lowered_for(monkeypatch):
    """`where_looped` runs its first function in a program for a platform where the gates loop,
    its second elsewhere (the two differ here on purpose, to show which ran)."""
    from octax_core.emulator import gate

    def program():
        return jax.jit(lambda x: gate.where_looped(lambda x: x + 1, lambda x: x + 2, x))

    looped = jax.default_backend() in gate.LOOPED_PLATFORMS
    assert int(program()(jnp.int32(0))) == (1 if looped else 2)
    on_host = program()(jax.device_put(jnp.int32(0), jax.devices("cpu")[0]))
    assert int(on_host) == (1 if "cpu" in gate.LOOPED_PLATFORMS else 2)
    monkeypatch.setattr(gate, "LOOPED_PLATFORMS", ())
    assert int(program()(jnp.int32(0))) == 2


def test_on_a_host_with_one_kind_of_backend_only_its_branch_is_traced(monkeypatch):
    """`platform_dependent` traces every branch, and gates nest, so an XO-CHIP machine's trace
    took twice as long as needed on a CPU-only host; there the one branch lowering would pick is
    traced alone. With other backends present (a GPU host) both are traced and lowering picks."""
    from octax_core.emulator import gate

    jax.devices()  # backends started, as before any real trace
    traced = []

    def which(name):
        return lambda x: (traced.append(name), x + 1)[1]

    jaxpr = jax.make_jaxpr(lambda x: gate.where_looped(which("looped"), which("always"), x))(jnp.int32(0))
    cpu_only = {d.platform for d in jax.devices()} == {"cpu"}
    if cpu_only:
        assert traced == ["looped"] and "platform_index" not in str(jaxpr)
    monkeypatch.setattr(gate, "_only_backends", lambda: {"cpu", "cuda"})
    traced.clear()
    jaxpr = jax.make_jaxpr(lambda x: gate.where_looped(which("looped"), which("always"), x))(jnp.int32(0))
    assert sorted(traced) == ["always", "looped"] and "platform_index" in str(jaxpr)
    monkeypatch.setattr(gate, "_only_backends", lambda: {"cuda"})
    traced.clear()
    jax.make_jaxpr(lambda x: gate.where_looped(which("looped"), which("always"), x))(jnp.int32(0))
    assert traced == ["always"]


def _archive(name: str) -> tuple[dict, bytes]:
    """An archive program's programs.json entry and ROM."""
    import json

    from octax_core.env.romstore import ARCHIVE_ROM_DIR

    return (json.loads((ARCHIVE_ROM_DIR / "programs.json").read_text())[name],
            (ARCHIVE_ROM_DIR / f"{name}.ch8").read_bytes())


def _holds(machines: int) -> np.ndarray:
    """(machines, 12) key masks: machine m holds a key for 8 frames, then nothing, each its own schedule."""
    return np.array([[(1 << ((h + m * 3) % 16)) if (h + m) % 2 else 0 for h in range(12)] for m in range(machines)],
                    np.uint32)


def _assert_the_gpu_form_plays_alike(monkeypatch, machine, state):
    """Plays `state` (a batch) 96 frames, 8 recorded frames a call with `_holds`' schedules, on the
    looped machine, then with every gate always running (the form GPUs get): the two are equal bit
    for bit, every recorded picture and every field of the final state. Returns the pictures."""
    from octax_core.emulator import gate

    holds = _holds(len(state.pc))

    def play():
        frame.frame_runner.cache_clear()  # a new trace, which reads LOOPED_PLATFORMS
        step = jax.jit(jax.vmap(lambda s, k: machine.run_frames(s, k, 8, record_screens=True)))
        loops = step.lower(state, jnp.asarray(holds[:, 0])).as_text().count("stablehlo.while")
        now, pictures = state, []
        for h in range(holds.shape[1]):
            now, screens = step(now, jnp.asarray(holds[:, h]))
            pictures.append(np.asarray(screens))
        return now, np.concatenate(pictures, axis=1), loops

    looped_state, looped_pictures, looped_loops = play()
    monkeypatch.setattr(gate, "LOOPED_PLATFORMS", ())
    always_state, always_pictures, always_loops = play()
    frame.frame_runner.cache_clear()
    if jax.default_backend() in gate.LOOPED_PLATFORMS:  # (elsewhere both runs are the always form)
        assert always_loops < looped_loops  # the gates' loops are gone from the program
    assert looped_pictures.any()
    np.testing.assert_array_equal(always_pictures, looped_pictures)
    for path, a, b in zip(jax.tree_util.tree_flatten_with_path(looped_state)[0],
                          jax.tree.leaves(always_state), jax.tree.leaves(looped_state)):
        if jnp.issubdtype(a.dtype, jax.dtypes.prng_key):
            a, b = jax.random.key_data(a), jax.random.key_data(b)
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b), err_msg=str(path[0]))
    return looped_pictures


def test_the_gpu_form_of_the_gates_plays_the_same_batch(monkeypatch):
    """The batched machine with every gate always running (the form GPUs get) equals the looped
    form bit for bit: 6 machines, each with its own key schedule, 96 frames. Three archive programs
    share the batch, two machines each: sens8tion (SUPER-CHIP: switches between hires and lores),
    OctoPartyMix (XO-CHIP, both planes in lores) and jub8-1 (XO-CHIP, both planes in hires), on one
    XO-CHIP machine (it runs every SUPER-CHIP opcode and has every gate): one program per form."""
    machine = octax_core.Machine("xochip", instructions_per_frame=30)
    roms = [_archive(name)[1] for name in ("sens8tion", "OctoPartyMix", "jub8-1") for _ in range(2)]
    states = [machine.boot(rom, key) for rom, key in zip(roms, jax.random.split(jax.random.key(3), 6))]
    state = jax.tree.map(lambda *leaves: jnp.stack(leaves), *states)
    pictures = _assert_the_gpu_form_plays_alike(monkeypatch, machine, state)  # (6, 96, planes, 64, 4)
    drew = pictures.reshape(6, 96, 2, -1).any(axis=(1, 3))  # (machine, plane)
    assert drew[:, 0].all() and list(drew[:, 1]) == [False, False, True, True, True, True]  # plane 2: XO-CHIP's


@pytest.mark.slow  # the fast test above plays a SUPER-CHIP and an XO-CHIP program in one batch
@pytest.mark.parametrize("name", ["sweetcopter", "superOctoTrackXO"])
def test_the_gpu_form_of_the_gates_plays_each_program_on_its_own_machine(name, monkeypatch):
    """The same, 4 machines of one archive program on its own machine (platform, quirks, tick rate)."""
    from octax_core.emulator.quirks import quirks_from_octo

    entry, rom = _archive(name)
    options = entry["options"]
    machine = octax_core.Machine(entry["platform"], quirks=quirks_from_octo(options),
                                 instructions_per_frame=int(options.get("tickrate", 20)))
    state = jax.vmap(lambda k: machine.boot(rom, k))(jax.random.split(jax.random.key(3), 4))
    _assert_the_gpu_form_plays_alike(monkeypatch, machine, state)


def test_the_rare_work_crosses_into_its_gate_as_one_word():
    """Every value each `cpu._Rare` field can take survives `_pack` and `_unpack` (the scrolls
    signed), and the fields fit one uint32: the gate's inputs are that word, Vx, Vy and the bytes
    at I, not a buffer per field."""
    ranges = {"needs": range(16), "hires": range(2), "clear_planes": range(4), "plane": range(4),
              "drawn": range(4), "scroll_x": (-4, 0, 4), "scroll_y": range(-15, 16), "n": range(16)}
    assert tuple(ranges) == cpu._Rare._fields and sum(bits for bits, _ in cpu._RARE_BITS) <= 32
    round_trip = jax.jit(lambda rare: cpu._unpack(cpu._pack(rare)))  # one compile: every case has 31 lanes
    for field, values in ranges.items():
        values = jnp.asarray(np.resize(list(values), 31), jnp.int32)  # each value at least once
        others = {name: jnp.full(values.shape, max(r), jnp.int32) for name, r in ranges.items() if name != field}
        rare = cpu._Rare(**others, **{field: values})
        unpacked = round_trip(rare)
        for name in cpu._Rare._fields:
            np.testing.assert_array_equal(getattr(unpacked, name), getattr(rare, name), err_msg=f"{field}: {name}")


@pytest.mark.parametrize("backends", [{"cpu", "cuda"}, {"cpu"}])
def test_an_instruction_has_a_gate_for_its_memory_write_and_one_for_its_rare_work(backends, monkeypatch):
    """Every platform's memory write is gated (few instructions write); SUPER-CHIP and XO-CHIP's
    rare work (scrolls, hires clears, plane 2, the grid's sprite) is one more gate at the
    instruction's top level, with its parts inside it. (A gate per part cost each batch a loop,
    a predicate and their inputs on every instruction.) Traced on a host with a GPU, each gate is
    `platform_dependent` (a cond) over the loop; on a CPU-only host, the loop alone."""
    from octax_core.emulator import gate

    monkeypatch.setattr(gate, "_only_backends", lambda: backends)
    gate_form, other = ("cond", "while") if len(backends) > 1 else ("while", "cond")
    for name, gates in (("chip8", 1), ("schip", 2), ("xochip", 2)):
        machine = octax_core.Machine(name)
        states = jax.vmap(lambda k: machine.boot(b"\x12\x00", k))(jax.random.split(jax.random.key(0), 4))
        instruction = jax.make_jaxpr(jax.vmap(lambda s, k: cpu.execute(machine.platform, machine.quirks, s, k)[0]))
        eqns = instruction(states, jnp.zeros(4, jnp.uint32)).jaxpr.eqns
        assert sum(e.primitive.name == gate_form for e in eqns) == gates, name
        assert not any(e.primitive.name == other for e in eqns), name


def _loop_bodies(hlo_text: str) -> dict[str, str]:
    """The compiled program's `while` bodies: {name: text}."""
    import re

    computations = {match.group(1): match.group(2) for match in
                    re.finditer(r"^(?:ENTRY )?%(\S+) .*?\{\n(.*?)\n\}", hlo_text, re.S | re.M)}
    return {name: computations[name] for name in set(re.findall(r"body=%([\w.\-]+)", hlo_text))}


@pytest.mark.parametrize("name", ["schip", "xochip"])
def test_the_instruction_loop_copies_no_screen(name):
    """On SUPER-CHIP and XO-CHIP the loops that run instructions (the instruction loop and the
    frame loop around it: the bodies with a loop inside) never copy the screen. The rare work's
    gate updates the screen in place, then plane 1's draw; with plane 1's collision read after
    the gate, XLA could not order that read before the draw's in-place write and copied the whole
    screen before the gate on every instruction (see `cpu._draw`). The gated bodies themselves
    (a scroll reads the surface it rewrites) may copy. CHIP-8 is left out: jitted like this,
    without the benchmarks' scan around it, XLA copies its drawn screen once an instruction.
    Reading its collision off the drawn screen instead removes that copy, but ran 15% slower on
    a 15-ipf program at N = 512 in the scan, where XLA copies nothing either way (docs/machine.md).
    The program read is the Pong test's (8 machines, 300 recorded frames, the platform's options):
    on a CPU host its compile is shared."""
    import re

    machine = pong_machine(name)
    states = jax.vmap(lambda k: machine.boot(b"\x00\xe0\x12\x00", k))(jax.random.split(jax.random.key(0), 8))
    keys = jnp.zeros(8, jnp.uint32)
    if jax.default_backend() != "cpu":  # XLA:CPU's program, also on a host with an accelerator
        states, keys = jax.device_put((states, keys), jax.devices("cpu")[0])  # (placed arrays: a compile of its own)
    text = pong_program(machine).lower(states, keys).compile().as_text()
    screen = re.escape("u32[" + ",".join(map(str, states.screen.shape)) + "]")
    looping = {body: code for body, code in _loop_bodies(text).items() if " while(" in code}
    assert looping  # the frame loop and the instruction loop at least
    for body, code in looping.items():
        assert not re.search(rf"= {screen}\S* copy\(", code), f"{name}: {body} copies the screen"
