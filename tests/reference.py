"""A plain-Python CHIP-8 interpreter that follows docs/machine.md, used as the test oracle.

Written for clarity, not speed: plain ints and lists, one if/elif dispatch, no jax and no numpy
(numpy appears only in ``snapshot``, to match the dict that ``octax_core.snapshot`` returns).

    ref = RefMachine(rom_bytes, "chip8", instructions_per_frame=11, rng=1)
    ref.run_frame(keys_mask)          # keys: int mask (bit k = key k) or 16 bools
    ref.snapshot()                    # same keys, dtypes and shapes as octax_core.snapshot
"""

import copy
from dataclasses import dataclass

import numpy as np

FONT_ADDRESS = 0x50
PROGRAM_ADDRESS = 0x200
MAX_PROGRAM_SIZE = 4096 - PROGRAM_ADDRESS
NO_KEY = 0xFF

# The common 4x5 hex digits 0..F, 5 bytes each.
FONT = bytes([
    0xF0, 0x90, 0x90, 0x90, 0xF0,  # 0
    0x20, 0x60, 0x20, 0x20, 0x70,  # 1
    0xF0, 0x10, 0xF0, 0x80, 0xF0,  # 2
    0xF0, 0x10, 0xF0, 0x10, 0xF0,  # 3
    0x90, 0x90, 0xF0, 0x10, 0x10,  # 4
    0xF0, 0x80, 0xF0, 0x10, 0xF0,  # 5
    0xF0, 0x80, 0xF0, 0x90, 0xF0,  # 6
    0xF0, 0x10, 0x20, 0x40, 0x40,  # 7
    0xF0, 0x90, 0xF0, 0x90, 0xF0,  # 8
    0xF0, 0x90, 0xF0, 0x10, 0xF0,  # 9
    0xF0, 0x90, 0xF0, 0x90, 0x90,  # A
    0xE0, 0x90, 0xE0, 0x90, 0xE0,  # B
    0xF0, 0x80, 0x80, 0x80, 0xF0,  # C
    0xE0, 0x90, 0x90, 0x90, 0xE0,  # D
    0xF0, 0x80, 0xF0, 0x80, 0xF0,  # E
    0xF0, 0x80, 0xF0, 0x80, 0x80,  # F
])


@dataclass(frozen=True)
class RefQuirks:
    """The six quirks, named after the Timendus quirks test."""

    vf_reset: bool
    memory_increment: bool
    display_wait: bool
    clipping: bool
    shift_uses_vy: bool
    jump_uses_vx: bool


PROFILES = {
    "chip8": RefQuirks(vf_reset=True, memory_increment=True, display_wait=True,
                       clipping=True, shift_uses_vy=True, jump_uses_vx=False),
    "schip": RefQuirks(vf_reset=False, memory_increment=False, display_wait=False,
                       clipping=True, shift_uses_vy=False, jump_uses_vx=True),
}


def xorshift32(r):
    """One xorshift32 step on a 32-bit int."""
    r ^= (r << 13) & 0xFFFFFFFF
    r ^= r >> 17
    r ^= (r << 5) & 0xFFFFFFFF
    return r


def keys_to_list(keys):
    """An int mask (bit k = key k) or 16 bools, as a list of 16 bools."""
    if isinstance(keys, (int, np.integer)):
        return [bool((int(keys) >> k) & 1) for k in range(16)]
    keys = [bool(k) for k in keys]
    assert len(keys) == 16, "keys must be an int mask or 16 bools"
    return keys


class RefMachine:
    """One CHIP-8 machine. ``quirks`` is a profile name or any object with the six quirk attributes."""

    def __init__(self, rom, quirks, instructions_per_frame=11, rng=1):
        rom = bytes(rom)
        assert 0 < len(rom) <= MAX_PROGRAM_SIZE, "program must be 1..3584 bytes"
        assert instructions_per_frame > 0
        assert rng & 0xFFFFFFFF != 0, "xorshift32 state must be nonzero"
        self.quirks = PROFILES[quirks] if isinstance(quirks, str) else quirks
        self.instructions_per_frame = instructions_per_frame

        self.memory = bytearray(4096)
        self.memory[FONT_ADDRESS:FONT_ADDRESS + len(FONT)] = FONT
        self.memory[PROGRAM_ADDRESS:PROGRAM_ADDRESS + len(rom)] = rom
        self.V = [0] * 16
        self.I = 0
        self.pc = PROGRAM_ADDRESS
        self.sp = 0
        self.stack = [0] * 16
        self.delay_timer = 0
        self.sound_timer = 0
        self.screen = [[False] * 64 for _ in range(32)]  # screen[y][x]
        self.rng = rng & 0xFFFFFFFF
        self.key_wait = NO_KEY
        self.rnd_ran = False      # did a CXNN run during the last run_frame
        self.last_opcode = None   # the opcode the last execute ran

    # ---- helpers -------------------------------------------------------------------------------

    def fetch(self):
        return (self.memory[self.pc] << 8) | self.memory[(self.pc + 1) & 0xFFF]

    def _set_pc(self, value):
        self.pc = value & 0xFFF

    def _draw(self, x, y, n):
        """DXYN: XOR n sprite rows at (Vx mod 64, Vy mod 32); returns 1 if a lit pixel was erased."""
        x0 = self.V[x] % 64
        y0 = self.V[y] % 32
        erased = 0
        for row in range(n):
            bits = self.memory[(self.I + row) & 0xFFF]
            py = y0 + row
            if py >= 32:
                if self.quirks.clipping:
                    continue
                py %= 32
            for col in range(8):
                if not (bits >> (7 - col)) & 1:
                    continue
                px = x0 + col
                if px >= 64:
                    if self.quirks.clipping:
                        continue
                    px %= 64
                if self.screen[py][px]:
                    erased = 1
                self.screen[py][px] = not self.screen[py][px]
        return erased

    # ---- one instruction -------------------------------------------------------------------------

    def execute(self, keys):
        """Run one instruction with ``keys`` held. No timer tick, no display_wait handling."""
        keys = keys_to_list(keys)
        op = self.fetch()
        self.last_opcode = op
        V = self.V
        q = self.quirks
        x = (op >> 8) & 0xF
        y = (op >> 4) & 0xF
        n = op & 0xF
        nn = op & 0xFF
        nnn = op & 0xFFF
        family = op >> 12
        next_pc = self.pc + 2
        skip_pc = self.pc + 4

        if op == 0x00E0:
            self.screen = [[False] * 64 for _ in range(32)]
        elif op == 0x00EE:
            self.sp = (self.sp - 1) % 16
            next_pc = self.stack[self.sp]
        elif family == 0x1:
            next_pc = nnn
        elif family == 0x2:
            # "Every address wraps at 4 KiB": the return address too (matters only at pc = 0xFFE).
            self.stack[self.sp] = (self.pc + 2) & 0xFFF
            self.sp = (self.sp + 1) % 16
            next_pc = nnn
        elif family == 0x3:
            if V[x] == nn:
                next_pc = skip_pc
        elif family == 0x4:
            if V[x] != nn:
                next_pc = skip_pc
        elif family == 0x5 and n == 0:
            if V[x] == V[y]:
                next_pc = skip_pc
        elif family == 0x6:
            V[x] = nn
        elif family == 0x7:
            V[x] = (V[x] + nn) % 256
        elif family == 0x8 and n in (0x0, 0x1, 0x2, 0x3):
            if n == 0x0:
                V[x] = V[y]
            elif n == 0x1:
                V[x] = V[x] | V[y]
            elif n == 0x2:
                V[x] = V[x] & V[y]
            else:
                V[x] = V[x] ^ V[y]
            if n != 0 and q.vf_reset:
                V[0xF] = 0
        elif family == 0x8 and n == 0x4:
            total = V[x] + V[y]
            V[x] = total % 256
            V[0xF] = 1 if total > 255 else 0
        elif family == 0x8 and n == 0x5:
            vx, vy = V[x], V[y]
            V[x] = (vx - vy) % 256
            V[0xF] = 1 if vx >= vy else 0
        elif family == 0x8 and n == 0x6:
            s = V[y] if q.shift_uses_vy else V[x]
            V[x] = s >> 1
            V[0xF] = s & 1
        elif family == 0x8 and n == 0x7:
            vx, vy = V[x], V[y]
            V[x] = (vy - vx) % 256
            V[0xF] = 1 if vy >= vx else 0
        elif family == 0x8 and n == 0xE:
            s = V[y] if q.shift_uses_vy else V[x]
            V[x] = (s << 1) % 256
            V[0xF] = s >> 7
        elif family == 0x9 and n == 0:
            if V[x] != V[y]:
                next_pc = skip_pc
        elif family == 0xA:
            self.I = nnn
        elif family == 0xB:
            offset = V[x] if q.jump_uses_vx else V[0]
            next_pc = nnn + offset
        elif family == 0xC:
            self.rng = xorshift32(self.rng)
            V[x] = (self.rng >> 24) & nn
            self.rnd_ran = True
        elif family == 0xD:
            if n == 0:
                V[0xF] = 0
            else:
                V[0xF] = self._draw(x, y, n)
        elif family == 0xE and nn == 0x9E:
            if keys[V[x] & 0xF]:
                next_pc = skip_pc
        elif family == 0xE and nn == 0xA1:
            if not keys[V[x] & 0xF]:
                next_pc = skip_pc
        elif family == 0xF and nn == 0x07:
            V[x] = self.delay_timer
        elif family == 0xF and nn == 0x0A:
            if self.key_wait == NO_KEY:
                held = [k for k in range(16) if keys[k]]
                if held:
                    self.key_wait = held[0]
                next_pc = self.pc  # still waiting
            elif keys[self.key_wait]:
                next_pc = self.pc  # remembered key still held
            else:
                V[x] = self.key_wait  # released: done
                self.key_wait = NO_KEY
        elif family == 0xF and nn == 0x15:
            self.delay_timer = V[x]
        elif family == 0xF and nn == 0x18:
            self.sound_timer = V[x]
        elif family == 0xF and nn == 0x1E:
            self.I = (self.I + V[x]) & 0xFFF
        elif family == 0xF and nn == 0x29:
            self.I = FONT_ADDRESS + 5 * (V[x] & 0xF)
        elif family == 0xF and nn == 0x33:
            value = V[x]
            self.memory[self.I] = value // 100
            self.memory[(self.I + 1) & 0xFFF] = (value // 10) % 10
            self.memory[(self.I + 2) & 0xFFF] = value % 10
        elif family == 0xF and nn == 0x55:
            for k in range(x + 1):
                self.memory[(self.I + k) & 0xFFF] = V[k]
            if q.memory_increment:
                self.I = (self.I + x + 1) & 0xFFF
        elif family == 0xF and nn == 0x65:
            for k in range(x + 1):
                V[k] = self.memory[(self.I + k) & 0xFFF]
            if q.memory_increment:
                self.I = (self.I + x + 1) & 0xFFF
        # anything else: no operation

        self._set_pc(next_pc)
        return op

    # ---- one frame --------------------------------------------------------------------------------

    def run_frame(self, keys):
        """Run one 60 Hz frame with ``keys`` held throughout, then tick the timers."""
        self.rnd_ran = False
        for _ in range(self.instructions_per_frame):
            op = self.execute(keys)
            if self.quirks.display_wait and op >> 12 == 0xD:
                break
        if self.delay_timer > 0:
            self.delay_timer -= 1
        if self.sound_timer > 0:
            self.sound_timer -= 1

    def run_frames(self, keys, frames):
        for _ in range(frames):
            self.run_frame(keys)

    # ---- inspection -------------------------------------------------------------------------------

    def snapshot(self):
        """The state as a dict of numpy arrays, like ``octax_core.snapshot`` of an unbatched state."""
        return {
            "memory": np.frombuffer(bytes(self.memory), dtype=np.uint8).copy(),
            "V": np.array(self.V, dtype=np.uint8),
            "I": np.array(self.I, dtype=np.uint16),
            "pc": np.array(self.pc, dtype=np.uint16),
            "sp": np.array(self.sp, dtype=np.uint8),
            "stack": np.array(self.stack, dtype=np.uint16),
            "delay_timer": np.array(self.delay_timer, dtype=np.uint8),
            "sound_timer": np.array(self.sound_timer, dtype=np.uint8),
            "screen": np.array(self.screen, dtype=bool),
            "rng": np.array(self.rng, dtype=np.uint32),
            "key_wait": np.array(self.key_wait, dtype=np.uint8),
        }

    def clone(self):
        """An independent copy (cheaper than copy.deepcopy)."""
        other = copy.copy(self)
        other.memory = bytearray(self.memory)
        other.V = list(self.V)
        other.stack = list(self.stack)
        other.screen = [list(row) for row in self.screen]
        return other

    def render_text(self, on="#", off="."):
        return "\n".join("".join(on if p else off for p in row) for row in self.screen)


# ---- comparing snapshots ---------------------------------------------------------------------------

FIELD_ORDER = ("pc", "V", "I", "sp", "stack", "delay_timer", "sound_timer", "key_wait", "rng",
               "memory", "screen")


def first_difference(expected, got):
    """None if two snapshots are equal (values, dtypes, shapes), else a description of the first
    differing field: its name, the first differing index and both values."""
    if set(expected) != set(got):
        return f"fields differ: expected {sorted(expected)}, got {sorted(got)}"
    for name in FIELD_ORDER + tuple(sorted(set(expected) - set(FIELD_ORDER))):
        want, have = np.asarray(expected[name]), np.asarray(got[name])
        if want.shape != have.shape or want.dtype != have.dtype:
            return (f"{name}: expected shape {want.shape} dtype {want.dtype}, "
                    f"got shape {have.shape} dtype {have.dtype}")
        if np.array_equal(want, have):
            continue
        if want.ndim == 0:
            return f"{name}: expected {_show(want)}, got {_show(have)}"
        unequal = np.argwhere(want != have)
        index = tuple(int(i) for i in unequal[0])
        where = f"[{', '.join(hex(i) if name == 'memory' else str(i) for i in index)}]"
        return (f"{name}{where}: expected {_show(want[index])}, got {_show(have[index])} "
                f"({len(unequal)} entries differ)")
    return None


def _show(value):
    value = np.asarray(value)
    return str(bool(value)) if value.dtype == np.bool_ else hex(int(value))
