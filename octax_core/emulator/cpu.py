"""Fetch, decode, execute: one instruction of any platform as a pure function of the state.

One executor for CHIP-8, SUPER-CHIP and XO-CHIP: what differs is data of the `Platform` (the
opcodes decoded, the bytes fetched, where addresses wrap, the mirrored bytes, the planes and
their grid), read here at trace time, so a CHIP-8 machine traces to CHIP-8's program alone.

Every handler runs on every instruction (under `vmap` there is no real branching), so handlers
return small effects and `execute` merges them field by field with scalar selects on the decoded
kind, then applies the merged effect once. Whatever the opcode, an instruction costs two
contiguous memory reads (the opcode, 16 bytes at I), one 16-byte window write (two, to keep the
mirror), a sprite drawn on plane 1 of the 64x32 surface, and a few lane selects on the
registers and the stack. The work few machines need on a given instruction (a hires sprite, a
sprite on XO-CHIP's second plane, a hires clear, a scroll) runs under one `gate.when_any`, each
part under its own inside it: the whole batch skips it when no machine needs it (`_draw`).
"""

from __future__ import annotations

from typing import NamedTuple, Optional

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator.decode import Decoded, decode
from octax_core.emulator.gate import any_of_batch, when_any, where_looped
from octax_core.emulator.opcodes import LEVELS, OPCODES, Kind
from octax_core.emulator.ops import Context, Effect, alu, display, extended, flow, keys, memory, timers
from octax_core.emulator.platforms import Platform
from octax_core.emulator.quirks import Quirks
from octax_core.emulator.state import MEMORY_OFFSET, Extension, MachineState

HANDLERS = {
    Kind.STALL: flow.op_stall,
    Kind.CLS: display.op_00e0,
    Kind.RET: flow.op_00ee,
    Kind.JP: flow.op_1nnn,
    Kind.CALL: flow.op_2nnn,
    Kind.SE_NN: flow.op_3xnn,
    Kind.SNE_NN: flow.op_4xnn,
    Kind.SE_XY: flow.op_5xy0,
    Kind.LD_NN: alu.op_6xnn,
    Kind.ADD_NN: alu.op_7xnn,
    Kind.LD_XY: alu.op_8xy0,
    Kind.OR: alu.op_8xy1,
    Kind.AND: alu.op_8xy2,
    Kind.XOR: alu.op_8xy3,
    Kind.ADD_XY: alu.op_8xy4,
    Kind.SUB: alu.op_8xy5,
    Kind.SHR: alu.op_8xy6,
    Kind.SUBN: alu.op_8xy7,
    Kind.SHL: alu.op_8xye,
    Kind.SNE_XY: flow.op_9xy0,
    Kind.LD_I: memory.op_annn,
    Kind.JP_V: flow.op_bnnn,
    Kind.RND: alu.op_cxnn,
    Kind.SKP: keys.op_ex9e,
    Kind.SKNP: keys.op_exa1,
    Kind.LD_VX_DT: timers.op_fx07,
    Kind.LD_KEY: keys.op_fx0a,
    Kind.LD_DT: timers.op_fx15,
    Kind.LD_ST: timers.op_fx18,
    Kind.ADD_I: memory.op_fx1e,
    Kind.LD_FONT: memory.op_fx29,
    Kind.BCD: memory.op_fx33,
    Kind.STORE: memory.op_fx55,
    Kind.LOAD: memory.op_fx65,
    # SUPER-CHIP
    Kind.SCROLL_DOWN: extended.op_00cn,
    Kind.SCROLL_RIGHT: extended.op_00fb,
    Kind.SCROLL_LEFT: extended.op_00fc,
    Kind.EXIT: extended.op_00fd,
    Kind.LORES: extended.op_00fe,
    Kind.HIRES: extended.op_00ff,
    Kind.LD_BIG_FONT: extended.op_fx30,
    Kind.SAVE_FLAGS: extended.op_fx75,
    Kind.LOAD_FLAGS: extended.op_fx85,
    # XO-CHIP
    Kind.SCROLL_UP: extended.op_00dn,
    Kind.SAVE_RANGE: extended.op_5xy2,
    Kind.LOAD_RANGE: extended.op_5xy3,
    Kind.LD_I_LONG: extended.op_f000,
    Kind.PLANE: extended.op_fn01,
    Kind.AUDIO: extended.op_f002,
    Kind.PITCH: extended.op_fx3a,
}  # Kind.NOP has no handler: every field keeps its default; DXYN's is added per instruction,
#    once its collision is known (`display.op_dxyn`)

_KIND_LEVEL = {row.kind: LEVELS[row.platform] for row in OPCODES if row.kind is not None}


def handlers(platform: Platform) -> dict:
    """The handlers of the kinds `platform`'s decoder can produce (DXYN's excepted)."""
    return {kind: handler for kind, handler in HANDLERS.items() if _KIND_LEVEL.get(kind, 0) <= platform.level}


class Fetched(NamedTuple):
    """The instruction at pc, decoded, and the context its handler reads."""

    fields: Decoded
    kind: jax.Array  # int32 Kind; STALL while the frame is over (display wait)
    context: Context
    at_i: jax.Array  # uint8 bytes at I: the 16 of the window, 32 (a 16x16 sprite) on SUPER-CHIP, 64 (two) on
    #                  XO-CHIP; as read, not widened: the gated draws take it as an input (`_Sprite`), a
    #                  buffer XLA fills on every instruction whether the gate runs or not, and int32 would
    #                  make it 4x the bytes (measured: docs/machine-log.md)


def fetch(platform: Platform, quirks: Quirks, state: MachineState, keys, stalled=None) -> Fetched:
    """Reads the opcode at pc (and on XO-CHIP the word after it) and the 16 bytes at I, decodes,
    and builds the handlers' context.

    Both reads are contiguous slices thanks to the RAM mirror (`state.MEMORY_OFFSET`): the
    window at I serves FX65's loads, CHIP-8's sprites and the read half of FX33/FX55's
    read-modify-write.
    """
    pc, I = state.pc.astype(jnp.int32), state.I.astype(jnp.int32)
    code = jax.lax.dynamic_slice(state.memory, (pc + MEMORY_OFFSET,), (platform.fetch_bytes,)).astype(jnp.int32)
    at_i = jax.lax.dynamic_slice(state.memory, (I + MEMORY_OFFSET,), (_bytes_at_i(platform),))
    window = at_i[:16].astype(jnp.int32)
    fields = decode(code[0], code[1], platform)
    kind = fields.kind if stalled is None else jnp.where(stalled, int(Kind.STALL), fields.kind)
    V, sp = state.V.astype(jnp.int32), state.sp.astype(jnp.int32)
    context = Context(
        quirks=quirks, x=fields.x, y=fields.y, n=fields.n, nn=fields.nn, nnn=fields.nnn, vx=V[fields.x],
        vy=V[fields.y], v0=V[0], pc=pc, I=I, sp=sp, stack_top=state.stack[(sp - 1) & 0xF].astype(jnp.int32),
        V=V, window=window, collision=jnp.bool_(False), keys=keys,
        delay_timer=state.delay_timer.astype(jnp.int32), rng=state.rng, key_wait=state.key_wait.astype(jnp.int32),
        plane=jnp.int32(1),
    )
    if platform.fetch_bytes == 4:  # a skip jumps over a whole instruction: 4 bytes when it is F000 NNNN
        next_word = (code[2] << 8) | code[3]
        context = context._replace(skip_bytes=jnp.where(next_word == 0xF000, 4, 2), next_word=next_word)
    if state.extension is not None:
        ext = state.extension
        context = context._replace(hires=ext.hires, flags=ext.flags.astype(jnp.int32),
                                   plane=ext.plane.astype(jnp.int32))
    return Fetched(fields, kind, context, at_i)


def merge(kind, effects: dict, defaults: Effect) -> Effect:
    """One effect: each field the value of the handler `kind` selects, where that handler sets
    it, else the field of `defaults`. No branching: a scalar field is a chain of scalar selects;
    a vector field (16 registers or bytes) one lookup in the stack of its candidates, since a
    chain of whole-vector selects costs 16 times as much per link, or one select where a single
    handler sets it (the stack and its lookup cost more than that select)."""
    merged = {}
    for field, default in zip(Effect._fields, defaults):
        if default is None:  # a field this platform does not have (SUPER-CHIP's, on CHIP-8)
            merged[field] = None
            continue
        setters = [(k, getattr(effect, field)) for k, effect in effects.items() if getattr(effect, field) is not None]
        if not setters:  # no handler of this platform sets it (XO-CHIP's audio, on SUPER-CHIP)
            value = default
        elif jnp.ndim(default) == 0:
            value = default
            for handler_kind, candidate in setters:
                value = jnp.where(kind == handler_kind, candidate, value)
        elif len(setters) == 1:  # one handler sets it (FX75's flags, F002's pattern): one select
            (handler_kind, candidate), = setters
            value = jnp.where(kind == handler_kind, jnp.asarray(candidate, default.dtype), default)
        else:
            row = np.zeros(len(Kind), np.int32)  # kind -> its row in the stack; 0: the default
            row[[int(k) for k, _ in setters]] = np.arange(1, len(setters) + 1)
            stack = jnp.stack([default] + [jnp.asarray(candidate, default.dtype) for _, candidate in setters])
            value = stack[jnp.asarray(row)[kind]]
        merged[field] = value
    return Effect(**merged)


def sets(kind, effects: dict, field: str) -> jax.Array:
    """Whether the handler `kind` selects sets `field` (for fields with no neutral default)."""
    kinds = [k for k, effect in effects.items() if getattr(effect, field) is not None]
    return jnp.isin(kind, jnp.asarray(kinds, jnp.int32))


def _defaults(state: MachineState, c: Context) -> Effect:
    """What an instruction leaves alone: pc moves on by 2, everything else stays as it is."""
    effect = Effect(pc=c.pc + 2, vx=c.vx, vf=jnp.int32(0), i=c.I, sp=c.sp, push=c.pc, mem_data=c.window,
                    mem_count=jnp.int32(0), load_count=jnp.int32(0), delay_timer=c.delay_timer,
                    sound_timer=state.sound_timer.astype(jnp.int32), rng=c.rng, key_wait=c.key_wait,
                    clear_planes=jnp.int32(0))
    if state.extension is None:
        return effect
    ext = state.extension
    return effect._replace(
        load_flags=jnp.bool_(False), v_lanes=jnp.zeros(16, jnp.bool_), v_values=c.V, scroll_x=jnp.int32(0),
        scroll_y=jnp.int32(0), hires=c.hires, exited=ext.exited, flags=c.flags, plane=c.plane,
        audio_pattern=ext.audio_pattern.astype(jnp.int32), pitch=ext.pitch.astype(jnp.int32),
    )


def execute(platform: Platform, quirks: Quirks, state: MachineState, keys: jax.Array, stalled=None):
    """Runs the instruction at pc: fetch and decode, every handler, merge, apply.

    Args:
        platform: the machine (static).
        quirks: the interpreter behaviour (static).
        state: one machine.
        keys: uint32 mask of held keys.
        stalled: bool; when true the frame is over (display wait, 00FD) and nothing changes.

    Returns:
        (new state, the int32 `Kind` that ran: STALL while stalled; `idle` reads it to know
        whether the instruction wrote memory or the screen).
    """
    fetched = fetch(platform, quirks, state, keys, stalled)
    kind, c = fetched.kind, fetched.context
    # The memory write goes first and DXYN, the one handler that reads the collision, after it:
    # its sprite is the bytes fetched at I before the write (16, 32 on SUPER-CHIP, 64 for XO-CHIP's
    # two planes). DXYN writes no memory, so those are the bytes it would see after the write, and
    # nothing reads memory after the write: XLA never has to copy the memory buffer to keep the old
    # version alive (a read of the old memory after the write makes XLA copy the whole memory, 64 KiB
    # on XO-CHIP, on every instruction).
    effects = {k: handler(c) for k, handler in handlers(platform).items()}
    defaults = _defaults(state, c)
    before_drawing = merge(kind, effects, defaults)  # all but DXYN's VF, which needs the collision
    written = _write_memory(platform, state.memory, before_drawing, c)
    screen, grid, collision = _draw(platform, quirks, state, fetched, kind == Kind.DRW, before_drawing)
    effects[Kind.DRW] = display.op_dxyn(c._replace(collision=collision))
    effect = merge(kind, effects, defaults)
    return _apply(platform, state, kind, effects, effect, written, screen, grid, c), kind


def _write_memory(platform: Platform, memory, effect: Effect, c: Context):
    """The merged effect's memory write: its first mem_count bytes at I, the rest unchanged.

    Few instructions write memory (FX33, FX55, XO-CHIP's 5XY2), so the write runs under
    `when_any`: a batch in which no machine writes, the common case, skips both window writes
    (measured: docs/machine-log.md). A machine that writes nothing gets the bytes it has written
    back."""
    lanes = jnp.arange(16, dtype=jnp.int32)
    written = jnp.where(lanes < effect.mem_count, effect.mem_data, c.window).astype(jnp.uint8)
    return when_any(effect.mem_count > 0, _write_window_at(platform), memory, (written, c.I))


def _write_window_at(platform: Platform):
    """`write_window` as `when_any`'s work: inputs (the 16 bytes, I)."""
    def write(memory, inputs):
        return write_window(platform, memory, *inputs)
    return write


def write_window(platform: Platform, memory, window, I):
    """Writes 16 bytes at address I, wrapping at the memory size, and keeps the mirror in step.

    The second write repeats the same bytes one RAM-length away when the window touches the
    mirrored start of RAM (I < `mirrored_bytes`) or runs past its end (the wrapped bytes land
    in RAM 0x000..); otherwise it rewrites the first window in place. Nothing reads memory after
    these writes, so XLA updates the buffer in place.
    """
    size = platform.memory_size
    memory = jax.lax.dynamic_update_slice(memory, window, (I + MEMORY_OFFSET,))
    other = jnp.where(I > size - 16, I - size, jnp.where(I < platform.mirrored_bytes, I + size, I))
    return jax.lax.dynamic_update_slice(memory, window, (other + MEMORY_OFFSET,))


def _bytes_at_i(platform: Platform) -> int:
    """How many bytes `fetch` reads at I: CHIP-8's 16 (the window, a sprite of up to 15 rows),
    a 16x16 sprite's 32 after it, and on two planes the 64 that hold both planes' sprites (plane
    2's starts at most 32 bytes after plane 1's). The RAM mirror (`mirrored_bytes`) keeps each
    read one contiguous slice."""
    if not platform.wide_sprites:
        return 16
    return 32 * platform.planes


class _Sprite(NamedTuple):
    """What a gated draw reads (`_draw_hires`, `_draw_second_plane`): the bytes fetched at I, the
    opcode's N, the planes the machine draws this sprite on (bits; 0 where it draws nothing on
    that surface, which makes the draw a no-op), and where."""

    at_i: jax.Array  # (32 * planes,) uint8
    n: jax.Array
    planes: jax.Array  # int32 bits: plane 1 = 1, plane 2 = 2
    x: jax.Array
    y: jax.Array


def _plane_data(sprite: _Sprite, plane: int):
    """The 32 bytes plane `plane` (0 or 1) draws from: plane 1's at I, plane 2's after plane 1's
    rows when both are drawn, else at I too. They are the memory before this instruction's write,
    which is the memory a draw sees: DXYN writes none (see `execute`)."""
    if plane == 0:
        return sprite.at_i[:32]
    size = jnp.where(sprite.n == 0, 32, sprite.n) * (sprite.planes & 1)  # plane 1's bytes, when it is drawn
    return jax.lax.dynamic_slice(sprite.at_i, (size,), (32,))


def _plane_patterns(sprite: _Sprite, planes: range):
    """((len(planes), 16) uint32 rows, zero on the planes the sprite is not drawn on; height).
    Only the platforms with planes get here, and all of them draw 16x16 at N = 0
    (`Platform.wide_sprites`)."""
    data = jnp.stack([_plane_data(sprite, plane) for plane in planes])
    patterns, height = display.sprite_patterns(data, sprite.n, wide_sprites=True)
    drawn = ((sprite.planes >> jnp.asarray(list(planes), jnp.int32)) & 1) == 1
    return jnp.where(drawn[:, None], patterns, jnp.uint32(0)), height


class _Needs(NamedTuple):
    """Whether a machine needs each gated work of this instruction (`_needs`)."""

    grid_change: jax.Array  # a hires scroll or clear
    screen_scroll: jax.Array  # a lores scroll
    second_plane: jax.Array  # a lores sprite on XO-CHIP's plane 2
    hires_sprite: jax.Array  # a sprite on the grid


class _Rare(NamedTuple):
    """What the rare work of an instruction reads (`_rare_work`), one machine's small integers.

    They cross into the gate packed in one uint32 (`_pack`, widths in `_RARE_BITS`): every
    separate input of a loop is a buffer XLA fills on every instruction, whether the loop runs
    or not (one kernel each; XLA:CPU fills a stack of them row by row, then transposes it). On a
    batch that never needs the gates, those fills are most of what the gates cost (measured:
    docs/machine-log.md)."""

    needs: jax.Array  # `_Needs` as bits: 1 grid change, 2 screen scroll, 4 second plane, 8 hires sprite
    hires: jax.Array  # 1 in 128x64 mode (before this instruction), else 0
    clear_planes: jax.Array  # the merged effect's cleared planes (bits)
    plane: jax.Array  # the selected planes (bits), which drawing and scrolling act on
    drawn: jax.Array  # the planes this instruction's sprite is drawn on (bits; 0 when it draws none)
    scroll_x: jax.Array  # the merged effect's scroll, in pixels of the mode's surface: -4, 0 or 4
    scroll_y: jax.Array  # -15..15
    n: jax.Array  # the sprite's N


# (bits, signed) of each `_Rare` field, packed from bit 0 up: 25 bits in all
_RARE_BITS = ((4, False), (1, False), (2, False), (2, False), (2, False), (5, True), (5, True), (4, False))


def _pack(rare: _Rare) -> jax.Array:
    """The fields of `rare` in one uint32 (two's complement where signed)."""
    word, at = jnp.uint32(0), 0
    for value, (bits, _) in zip(rare, _RARE_BITS):
        word = word | ((jnp.asarray(value).astype(jnp.uint32) & ((1 << bits) - 1)) << at)
        at += bits
    return word


def _unpack(word) -> _Rare:
    """`_pack`'s inverse: int32 fields."""
    fields, at = [], 0
    for bits, signed in _RARE_BITS:
        value = ((word >> at) & ((1 << bits) - 1)).astype(jnp.int32)
        fields.append(jnp.where(value >= 1 << (bits - 1), value - (1 << bits), value) if signed else value)
        at += bits
    return _Rare(*fields)


_NEEDS_BITS = tuple(1 << k for k in range(len(_Needs._fields)))


def _needs(platform: Platform, c: Context, effect: Effect, drawing) -> _Needs:
    """Each gated work's predicate for this machine (SUPER-CHIP and XO-CHIP)."""
    moving = (effect.scroll_x != 0) | (effect.scroll_y != 0)
    drawn = jnp.where(drawing, c.plane, 0)
    second = ~c.hires & ((drawn & 2) != 0) if platform.planes > 1 else jnp.bool_(False)
    return _Needs(c.hires & ((effect.clear_planes != 0) | moving), ~c.hires & moving, second,
                  c.hires & (drawn != 0))


def _draw(platform: Platform, quirks: Quirks, state: MachineState, fetched: Fetched, drawing, effect: Effect):
    """DXYN, the clears and the scrolls: (the 64x32 screen, the grid, the collision).

    The 64x32 surface (CHIP-8's screen; the lores screen of SUPER-CHIP and XO-CHIP) is cleared
    and drawn by every machine on plane 1 (a zero mask where it does not draw). The rest (a
    scroll, a hires clear, XO-CHIP's plane 2, the 128x64 grid) is rare work: it runs under one
    `when_any`, when some machine of the batch needs some of it, and inside that each part
    under its own (`_rare_work`). A CHIP-8 program run by SUPER-CHIP or XO-CHIP pays for one
    predicate, one packed input and one loop that does not run. An instruction draws, clears
    or scrolls, never two of these, so their order is free: the rare work goes first, straight
    on the state's surfaces, and plane 1's clear and draw after it.

    Where the gate is a loop (a CPU), plane 1's collision is read off the state's screen, before
    the rare work, and enters the gate as its collision operand. It is the same as after it: a
    machine whose mask draws on plane 1 is drawing a lores sprite, and the rare work leaves plane
    1 of such a machine as it is (it draws plane 2 at most). The order matters to XLA:CPU: read
    after the loop, the screen had two readers, the collision and plane 1's draw, that XLA could
    not order before the draw's in-place write, and it copied the screen before the loop on every
    instruction. CHIP-8 reads it the same way, before its draw. Where the gate always runs (a
    GPU) there is no loop, so no copy to avoid, and the first order measured slower there, so
    there it is read after the rare work (`gate.where_looped` picks). The copy's cost and the
    GPU's timings: docs/machine-log.md.
    """
    c, n = fetched.context, fetched.fields.n
    if not platform.extended:
        patterns, height = display.sprite_patterns(fetched.at_i, n, False)
        mask = display.sprite_mask(patterns, c.vx & 63, c.vy & 31, jnp.where(drawing, height, 0), display.LORES,
                                   quirks.clipping)
        return _draw_lores(platform, state.screen, mask, effect, c), None, display.collides(state.screen, mask)
    drawn = jnp.where(drawing, c.plane, 0)
    lores = _Sprite(fetched.at_i, n, jnp.where(c.hires, 0, drawn), c.vx & 63, c.vy & 31)
    patterns, height = _plane_patterns(lores, range(1))
    mask = display.sprite_mask(patterns, lores.x, lores.y, height, display.LORES, quirks.clipping)
    needs = _needs(platform, c, effect, drawing)
    rare = _Rare(needs=sum(jnp.where(need, bit, 0) for need, bit in zip(needs, _NEEDS_BITS)),
                 hires=c.hires, clear_planes=effect.clear_planes, plane=c.plane, drawn=drawn,
                 scroll_x=effect.scroll_x, scroll_y=effect.scroll_y, n=n)
    # `when_any`'s work may close over constants only: a mix's per-machine clipping is an input
    fixed = isinstance(quirks.clipping, bool)
    needed = needs.grid_change | needs.screen_scroll | needs.second_plane | needs.hires_sprite
    work = _rare_work(platform, quirks.clipping if fixed else None)
    inputs = (_pack(rare), c.vx, c.vy, fetched.at_i, None if fixed else quirks.clipping)

    def collision_first(screen, grid):  # where the gate loops: plane 1's collision enters it
        return when_any(needed, work, (screen, grid, display.collides(screen[:1], mask)), inputs)

    def collision_after(screen, grid):  # where it always runs: ORed in after it
        screen, grid, collision = when_any(needed, work, (screen, grid, jnp.bool_(False)), inputs)
        return screen, grid, collision | display.collides(screen[:1], mask)

    screen, grid, collision = where_looped(collision_first, collision_after, state.screen, state.extension.grid)
    if platform.planes > 1:  # plane 2's mask is zero here: `_draw_second_plane` drew it
        mask = jnp.concatenate([mask, jnp.zeros_like(mask)])
    return _draw_lores(platform, screen, mask, effect, c), grid, collision


def _rare_work(platform: Platform, clipping):
    """The rare work of an instruction, each part under its own `when_any` (one reduction gives
    their predicates, `gate.any_of_batch`): a hires scroll or clear, a lores scroll, XO-CHIP's
    plane 2 sprite, a sprite on the grid. Operands (screen, grid, collision), the collision
    plane 1's or false on entry (`_draw`) and, on the way out, plane 2's ORed in, or the grid's
    on a machine in hires (whose plane 1 collision is false: its lores mask is zero); a no-op for
    a machine that needs none of it. `clipping` a constant, or None to read the machine's own
    from the inputs (a mix of profiles)."""
    def work(operands, inputs):
        (screen, grid, collision), (packed, x, y, at_i, own_clipping) = operands, inputs
        rare = _unpack(packed)
        needs = _Needs(*any_of_batch(*((rare.needs & bit) != 0 for bit in _NEEDS_BITS)))
        hires = rare.hires != 0
        planes = jnp.arange(platform.planes, dtype=jnp.int32)
        cleared = ((rare.clear_planes >> planes) & 1) == 1
        selected = ((rare.plane >> planes) & 1) == 1

        def amounts(mode):  # a scroll moves the surface of the machine's mode; the other one stays
            return jnp.where(mode, rare.scroll_x, 0), jnp.where(mode, rare.scroll_y, 0)

        grid = when_any(needs.grid_change, _scroll_planes, grid, (cleared & hires, selected, *amounts(hires)))
        screen = when_any(needs.screen_scroll, _scroll_planes, screen,
                          (jnp.zeros_like(cleared), selected, *amounts(~hires)))
        if platform.planes > 1:
            lores = _Sprite(at_i, rare.n, jnp.where(hires, 0, rare.drawn), x & 63, y & 31)
            screen, collision = when_any(needs.second_plane, _draw_second_plane(clipping), (screen, collision),
                                         (lores, own_clipping))
        sprite = _Sprite(at_i, rare.n, jnp.where(hires, rare.drawn, 0), x & 127, y & 63)
        grid, hires_collision = when_any(needs.hires_sprite, _draw_hires(platform, clipping),
                                         (grid, jnp.bool_(False)), (sprite, own_clipping))
        return screen, grid, jnp.where(hires, hires_collision, collision)
    return work


def _scroll_planes(surface, inputs):
    """Clears the `cleared` planes of a (planes, rows, words) surface, then scrolls the selected
    ones by (dx, dy) pixels of that surface. No-op where nothing is cleared and dx = dy = 0."""
    cleared, selected, dx, dy = inputs
    surface = jnp.where(cleared[:, None, None], jnp.uint32(0), surface)
    return jnp.where(selected[:, None, None], display.scroll(surface, dx, dy), surface)


def _draw_second_plane(clipping):
    """XO-CHIP's plane 2 drawn on the 64x32 screen, under `when_any`: the collision of plane 1's
    draw or of this one. `clipping` a constant, or None to read the machine's own from the inputs
    (a mix of profiles)."""
    def draw(operands, inputs):
        (screen, collision), (sprite, own_clipping) = operands, inputs
        patterns, height = _plane_patterns(sprite, range(1, 2))
        mask = display.sprite_mask(patterns, sprite.x, sprite.y, height, display.LORES,
                                   clipping if own_clipping is None else own_clipping)
        return screen ^ jnp.concatenate([jnp.zeros_like(mask), mask]), collision | display.collides(screen[1:], mask)
    return draw


def _draw_hires(platform: Platform, clipping):
    """The hires draw under `when_any`, every plane: `clipping` a constant, or None to read the
    machine's own from the inputs (a mix of profiles)."""
    def draw(operands, inputs):
        (grid, _), (sprite, own_clipping) = operands, inputs
        patterns, height = _plane_patterns(sprite, range(platform.planes))
        mask = display.sprite_mask(patterns, sprite.x, sprite.y, height, display.HIRES,
                                   clipping if own_clipping is None else own_clipping)
        return grid ^ mask, display.collides(grid, mask)
    return draw


def _draw_lores(platform: Platform, screen, mask, effect: Effect, c: Context):
    """The 64x32 screen after the merged effect's clear and sprite: one AND and one XOR, for
    every machine (a machine in hires keeps all, its mask is 0: its 64x32 screen is dark)."""
    if not platform.extended:
        return (screen & jnp.where(effect.clear_planes != 0, jnp.uint32(0), jnp.uint32(0xFFFFFFFF))) ^ mask
    cleared = ((effect.clear_planes >> jnp.arange(platform.planes, dtype=jnp.int32)) & 1) == 1
    keep = jnp.where(cleared & ~c.hires, jnp.uint32(0), jnp.uint32(0xFFFFFFFF))[:, None, None]
    return (screen & keep) ^ mask


def _apply(platform: Platform, state: MachineState, kind, effects: dict, effect: Effect, memory, screen, grid,
           c: Context) -> MachineState:
    """The merged effect applied once: registers by lane selects with VF after Vx (a scatter at
    x would cost more under vmap), the stack push, I, pc (wrapped at the memory size), timers,
    the screen, and the extension's fields."""
    lanes = jnp.arange(16, dtype=jnp.int32)
    V = jnp.where(lanes == c.x, effect.vx, c.V)
    loaded = c.window if effect.load_flags is None else jnp.where(effect.load_flags, c.flags, c.window)
    V = jnp.where(lanes < effect.load_count, loaded, V)  # FX65, FX85: after Vx, which they leave
    if effect.v_lanes is not None:
        V = jnp.where(effect.v_lanes, effect.v_values, V)
    V = jnp.where((lanes == 15) & sets(kind, effects, "vf"), effect.vf, V)
    pushing = (lanes == c.sp) & sets(kind, effects, "push")
    address_mask = platform.address_mask
    extension = None
    if state.extension is not None:
        extension = Extension(hires=effect.hires, grid=grid, flags=effect.flags.astype(jnp.uint8), exited=effect.exited,
                              plane=effect.plane.astype(jnp.uint8),
                              audio_pattern=effect.audio_pattern.astype(jnp.uint8), pitch=effect.pitch.astype(jnp.uint8))
    return MachineState(
        memory=memory,
        V=V.astype(jnp.uint8),
        I=(effect.i & address_mask).astype(jnp.uint16),
        pc=(effect.pc & address_mask).astype(jnp.uint16),
        sp=effect.sp.astype(jnp.uint8),
        stack=jnp.where(pushing, effect.push & address_mask, state.stack).astype(jnp.uint16),
        delay_timer=effect.delay_timer.astype(jnp.uint8),
        sound_timer=effect.sound_timer.astype(jnp.uint8),
        screen=screen,
        rng=effect.rng,
        key_wait=effect.key_wait.astype(jnp.uint8),
        extension=extension,
    )


def tick_timers(state: MachineState, ticking=True) -> MachineState:
    """The 60 Hz tick where `ticking`: each nonzero timer drops by one."""
    def tick(timer):
        return jnp.where(ticking & (timer > 0), timer - 1, timer).astype(timer.dtype)
    return state.replace(delay_timer=tick(state.delay_timer), sound_timer=tick(state.sound_timer))
