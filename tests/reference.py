"""A plain-Python CHIP-8, SUPER-CHIP and XO-CHIP interpreter, used as the test oracle.

CHIP-8 follows docs/machine.md. SUPER-CHIP and XO-CHIP follow the contract of issue 12 (Octo's
modern behaviour), written from that specification and not from the JAX core:

* ``platform="schip"``: 4 KiB, one 128x64 plane. 00FF/00FE switch to hires/lores and clear the
  screen; in lores a pixel is a 2x2 block of the grid and coordinates, sprites and scroll amounts
  are in lores pixels. 00CN scrolls down N rows, 00FB/00FC right/left 4 pixels, DXY0 draws 16x16
  (two bytes a row), VF = 1 if any pixel was erased (the modern rule: the HP48's count of rows
  is not modelled), FX30 points I at a big digit (0xA0 + 10 x digit), FX75/FX85 save/load
  V0..VX to 16 flag registers, 00FD exits: the machine stops, and nothing changes after.
* ``platform="xochip"``: the above, 64 KiB (addresses wrap at 0x10000), two planes. F000 NNNN
  loads a 16-bit I (and every skip skips the whole 4-byte instruction), 5XY2/5XY3 save/load
  VX..VY in either order without moving I, FN01 selects planes (bit 0 plane 1, bit 1 plane 2),
  00E0, drawing and scrolling act on the selected planes only (a sprite's data for plane 1 first,
  then plane 2's), 00DN scrolls up N rows, F002 loads the 16-byte audio pattern from I, FX3A sets
  the pitch.

On the chip8 platform none of these opcodes exists (each is a no-op, F000 a 2-byte one).

Written for clarity, not speed: plain ints and lists, one if/elif dispatch, no jax and no numpy
(numpy appears only in ``snapshot``, to match the dict that ``octax_core.snapshot`` returns).

    ref = RefMachine(rom_bytes, "chip8", instructions_per_frame=11, rng=1)
    ref.run_frame(keys_mask)          # keys: int mask (bit k = key k) or 16 bools
    ref.snapshot()                    # same keys, dtypes and shapes as octax_core.snapshot
    RefMachine(rom, "schip", platform="schip")   # or "xochip", with its own quirks profile
"""

import copy
from dataclasses import dataclass

import numpy as np

FONT_ADDRESS = 0x50
PROGRAM_ADDRESS = 0x200
MAX_PROGRAM_SIZE = 4096 - PROGRAM_ADDRESS
NO_KEY = 0xFF
BIG_FONT_ADDRESS = 0xA0  # the 16 big digits follow the small font's 80 bytes
MEMORY_SIZE = {"chip8": 4096, "schip": 4096, "xochip": 65536}
PLATFORMS = tuple(MEMORY_SIZE)

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

# The 16 big digits (SUPER-CHIP FX30; XO-CHIP has them too), 8x10 pixels, one byte a row.
BIG_DIGITS = """
########  ...##...  ########  ########  ##....##  ########  ########  ########
########  .####...  ########  ########  ##....##  ########  ########  ########
##....##  .####...  ......##  ......##  ##....##  ##......  ##......  ......##
##....##  ...##...  ......##  ......##  ##....##  ##......  ##......  ......##
##....##  ...##...  ########  ########  ########  ########  ########  .....##.
##....##  ...##...  ########  ########  ########  ########  ########  ....##..
##....##  ...##...  ##......  ......##  ......##  ......##  ##....##  ...##...
##....##  ...##...  ##......  ......##  ......##  ......##  ##....##  ...##...
########  ########  ########  ########  ......##  ########  ########  ...##...
########  ########  ########  ########  ......##  ########  ########  ...##...

########  ########  .######.  ######..  ..####..  ######..  ########  ########
########  ########  ########  ######..  ########  #######.  ########  ########
##....##  ##....##  ##....##  ##....##  ##....##  ##....##  ##......  ##......
##....##  ##....##  ##....##  ##....##  ##......  ##....##  ##......  ##......
########  ########  ##....##  ######..  ##......  ##....##  ########  ########
########  ########  ########  ######..  ##......  ##....##  ########  ########
##....##  ......##  ########  ##....##  ##......  ##....##  ##......  ##......
##....##  ......##  ##....##  ##....##  ##....##  ##....##  ##......  ##......
########  ########  ##....##  ######..  ########  #######.  ########  ##......
########  ########  ##....##  ######..  ..####..  ######..  ########  ##......
"""


def _big_font(art: str) -> bytes:
    """The digits' bytes, 0 to F, from the picture above (two rows of eight digits)."""
    rows = [line.split() for line in art.strip().splitlines() if line.strip()]
    digits = [[row[d] for row in rows[block * 10:(block + 1) * 10]] for block in (0, 1) for d in range(8)]
    return bytes(int(line.replace("#", "1").replace(".", "0"), 2) for digit in digits for line in digit)


BIG_FONT = _big_font(BIG_DIGITS)


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
    "xochip": RefQuirks(vf_reset=False, memory_increment=True, display_wait=False,
                        clipping=False, shift_uses_vy=True, jump_uses_vx=False),
}


def xorshift32(r):
    """One xorshift32 step on a 32-bit int."""
    r ^= (r << 13) & 0xFFFFFFFF
    r ^= r >> 17
    r ^= (r << 5) & 0xFFFFFFFF
    return r


def assemble(*words):
    """16-bit opcode words as program bytes, big-endian."""
    return b"".join(w.to_bytes(2, "big") for w in words)


def keys_to_list(keys):
    """An int mask (bit k = key k) or 16 bools, as a list of 16 bools."""
    if isinstance(keys, (int, np.integer)):
        return [bool((int(keys) >> k) & 1) for k in range(16)]
    keys = [bool(k) for k in keys]
    assert len(keys) == 16, "keys must be an int mask or 16 bools"
    return keys


class RefMachine:
    """One machine. ``quirks`` is a profile name or any object with the six quirk attributes;
    ``platform`` ("chip8", "schip" or "xochip") chooses the opcodes, memory and display."""

    def __init__(self, rom, quirks, instructions_per_frame=11, rng=1, platform="chip8"):
        rom = bytes(rom)
        assert platform in PLATFORMS, f"platform must be one of {PLATFORMS}"
        self.platform = platform
        self.memory_size = MEMORY_SIZE[platform]
        assert 0 < len(rom) <= self.memory_size - PROGRAM_ADDRESS, "program too large for its platform"
        assert instructions_per_frame > 0
        assert rng & 0xFFFFFFFF != 0, "xorshift32 state must be nonzero"
        self.quirks = PROFILES[quirks] if isinstance(quirks, str) else quirks
        self.instructions_per_frame = instructions_per_frame

        self.memory = bytearray(self.memory_size)
        self.memory[FONT_ADDRESS:FONT_ADDRESS + len(FONT)] = FONT
        if platform != "chip8":
            self.memory[BIG_FONT_ADDRESS:BIG_FONT_ADDRESS + len(BIG_FONT)] = BIG_FONT
        self.memory[PROGRAM_ADDRESS:PROGRAM_ADDRESS + len(rom)] = rom
        self.V = [0] * 16
        self.I = 0
        self.pc = PROGRAM_ADDRESS
        self.sp = 0
        self.stack = [0] * 16
        self.delay_timer = 0
        self.sound_timer = 0
        if platform == "chip8":
            self.screen = [[False] * 64 for _ in range(32)]  # screen[y][x]
        else:  # planes[p][y][x] on the 128x64 grid; schip has plane 0 only
            self.planes = [[[False] * 128 for _ in range(64)] for _ in range(2 if platform == "xochip" else 1)]
            self.hires = False
            self.flags = [0] * 16
            self.plane = 1  # the selected planes (XO-CHIP FN01); schip always draws on plane 1
            self.audio_pattern = [0] * 16
            self.pitch = 64
        self.exited = False       # 00FD ran (SUPER-CHIP and XO-CHIP only; shown in their snapshots)
        self.rng = rng & 0xFFFFFFFF
        self.key_wait = NO_KEY
        self.rnd_ran = False      # did a CXNN run during the last run_frame
        self.last_opcode = None   # the opcode the last execute ran

    # ---- helpers -------------------------------------------------------------------------------

    def _mem(self, address):
        return self.memory[address % self.memory_size]

    def fetch(self):
        return (self._mem(self.pc) << 8) | self._mem(self.pc + 1)

    def _set_pc(self, value):
        self.pc = value % self.memory_size

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

    # ---- SUPER-CHIP and XO-CHIP display --------------------------------------------------------------

    def _scale(self):
        """Grid pixels per screen pixel: 1 in hires, 2 in lores."""
        return 1 if self.hires else 2

    def _selected(self):
        """The indices of the planes that drawing, clearing and scrolling act on, plane 1 first."""
        return [p for p in range(len(self.planes)) if (self.plane >> p) & 1]

    def _clear(self, planes):
        for p in planes:
            self.planes[p] = [[False] * 128 for _ in range(64)]

    def _scroll(self, dx, dy):
        """Moves the selected planes by (dx, dy) screen pixels; what comes in is dark."""
        dx, dy = dx * self._scale(), dy * self._scale()
        for p in self._selected():
            old = self.planes[p]
            self.planes[p] = [[0 <= gx - dx < 128 and 0 <= gy - dy < 64 and old[gy - dy][gx - dx]
                               for gx in range(128)] for gy in range(64)]

    def _draw_planes(self, x, y, n):
        """DXYN/DXY0 on the 128x64 grid; returns 1 if any lit pixel of any plane was erased."""
        width, height = (16, 16) if n == 0 else (8, n)
        row_bytes = width // 8
        screen_w, screen_h = (128, 64) if self.hires else (64, 32)
        s = self._scale()
        x0, y0 = self.V[x] % screen_w, self.V[y] % screen_h
        erased = 0
        address = self.I
        for p in self._selected():
            for row in range(height):
                bits = 0
                for b in range(row_bytes):
                    bits = (bits << 8) | self._mem(address + row * row_bytes + b)
                for col in range(width):
                    if not (bits >> (width - 1 - col)) & 1:
                        continue
                    px, py = x0 + col, y0 + row
                    if px >= screen_w or py >= screen_h:
                        if self.quirks.clipping:
                            continue
                        px, py = px % screen_w, py % screen_h
                    lit = self.planes[p][py * s][px * s]
                    erased |= lit
                    for gy in range(py * s, py * s + s):
                        for gx in range(px * s, px * s + s):
                            self.planes[p][gy][gx] = not lit
            address += height * row_bytes
        return int(erased)

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
        size = self.memory_size
        ext = self.platform != "chip8"   # SUPER-CHIP's opcodes (XO-CHIP has them too)
        xo = self.platform == "xochip"
        next_pc = self.pc + 2
        # A skip skips a whole instruction: 4 bytes for XO-CHIP's F000 NNNN.
        skip_pc = self.pc + (6 if xo and (self._mem(self.pc + 2) << 8 | self._mem(self.pc + 3)) == 0xF000 else 4)

        if ext and op == 0x00E0:
            self._clear(self._selected())
        elif ext and op in (0x00FE, 0x00FF):
            self.hires = op == 0x00FF
            self._clear(range(len(self.planes)))
        elif ext and op & 0xFFF0 == 0x00C0:
            self._scroll(0, n)
        elif xo and op & 0xFFF0 == 0x00D0:
            self._scroll(0, -n)
        elif ext and op in (0x00FB, 0x00FC):
            self._scroll(4 if op == 0x00FB else -4, 0)
        elif ext and op == 0x00FD:
            self.exited = True
            next_pc = self.pc
        elif ext and family == 0xD:
            V[0xF] = self._draw_planes(x, y, n)
        elif ext and family == 0xF and nn == 0x30:
            self.I = BIG_FONT_ADDRESS + 10 * (V[x] & 0xF)
        elif ext and family == 0xF and nn == 0x75:
            self.flags[:x + 1] = V[:x + 1]
        elif ext and family == 0xF and nn == 0x85:
            V[:x + 1] = self.flags[:x + 1]
        elif xo and op == 0xF000:
            self.I = self._mem(self.pc + 2) << 8 | self._mem(self.pc + 3)
            next_pc = self.pc + 4
        elif xo and family == 0x5 and n in (0x2, 0x3):
            registers = range(x, y + 1) if x <= y else range(x, y - 1, -1)
            for k, r in enumerate(registers):
                if n == 0x2:
                    self.memory[(self.I + k) % size] = V[r]
                else:
                    V[r] = self._mem(self.I + k)
        elif xo and family == 0xF and nn == 0x01 and x <= 3:  # planes 0..3; F401.. are unknown
            self.plane = x
        elif xo and op == 0xF002:
            self.audio_pattern = [self._mem(self.I + k) for k in range(16)]
        elif xo and family == 0xF and nn == 0x3A:
            self.pitch = V[x]
        elif op == 0x00E0:
            self.screen = [[False] * 64 for _ in range(32)]
        elif op == 0x00EE:
            self.sp = (self.sp - 1) % 16
            next_pc = self.stack[self.sp]
        elif family == 0x1:
            next_pc = nnn
        elif family == 0x2:
            # "Every address wraps" (4 KiB, 64 KiB on xochip): the return address too.
            self.stack[self.sp] = (self.pc + 2) % size
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
            self.I = (self.I + V[x]) % size
        elif family == 0xF and nn == 0x29:
            self.I = FONT_ADDRESS + 5 * (V[x] & 0xF)
        elif family == 0xF and nn == 0x33:
            value = V[x]
            self.memory[self.I % size] = value // 100
            self.memory[(self.I + 1) % size] = (value // 10) % 10
            self.memory[(self.I + 2) % size] = value % 10
        elif family == 0xF and nn == 0x55:
            for k in range(x + 1):
                self.memory[(self.I + k) % size] = V[k]
            if q.memory_increment:
                self.I = (self.I + x + 1) % size
        elif family == 0xF and nn == 0x65:
            for k in range(x + 1):
                V[k] = self._mem(self.I + k)
            if q.memory_increment:
                self.I = (self.I + x + 1) % size
        # anything else: no operation

        self._set_pc(next_pc)
        return op

    # ---- one frame --------------------------------------------------------------------------------

    def run_frame(self, keys):
        """Run one 60 Hz frame with ``keys`` held throughout, then tick the timers. A frame
        that starts after 00FD (SUPER-CHIP exit) does nothing at all; the frame of the 00FD
        stops there and still ticks its timers."""
        self.rnd_ran = False
        if self.exited:
            return
        for _ in range(self.instructions_per_frame):
            op = self.execute(keys)
            if self.quirks.display_wait and op >> 12 == 0xD or self.exited:
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
        """The state as a dict of numpy arrays, like ``octax_core.snapshot`` of an unbatched state.

        schip and xochip add ``hires``, ``flags`` and ``exited``, xochip also ``plane``,
        ``audio_pattern`` and ``pitch``; their ``screen`` is the (64, 128) grid, for xochip
        (2, 64, 128) with plane 1 first."""
        snap = {
            "memory": np.frombuffer(bytes(self.memory), dtype=np.uint8).copy(),
            "V": np.array(self.V, dtype=np.uint8),
            "I": np.array(self.I, dtype=np.uint16),
            "pc": np.array(self.pc, dtype=np.uint16),
            "sp": np.array(self.sp, dtype=np.uint8),
            "stack": np.array(self.stack, dtype=np.uint16),
            "delay_timer": np.array(self.delay_timer, dtype=np.uint8),
            "sound_timer": np.array(self.sound_timer, dtype=np.uint8),
            "rng": np.array(self.rng, dtype=np.uint32),
            "key_wait": np.array(self.key_wait, dtype=np.uint8),
        }
        if self.platform == "chip8":
            snap["screen"] = np.array(self.screen, dtype=bool)
            return snap
        planes = np.array(self.planes, dtype=bool)
        snap["screen"] = planes[0] if self.platform == "schip" else planes
        snap["hires"] = np.array(self.hires, dtype=bool)
        snap["flags"] = np.array(self.flags, dtype=np.uint8)
        snap["exited"] = np.array(self.exited, dtype=bool)
        if self.platform == "xochip":
            snap["plane"] = np.array(self.plane, dtype=np.uint8)
            snap["audio_pattern"] = np.array(self.audio_pattern, dtype=np.uint8)
            snap["pitch"] = np.array(self.pitch, dtype=np.uint8)
        return snap

    def clone(self):
        """An independent copy (cheaper than copy.deepcopy)."""
        other = copy.copy(self)
        other.memory = bytearray(self.memory)
        other.V = list(self.V)
        other.stack = list(self.stack)
        if self.platform == "chip8":
            other.screen = [list(row) for row in self.screen]
        else:
            other.planes = [[list(row) for row in plane] for plane in self.planes]
            other.flags = list(self.flags)
            other.audio_pattern = list(self.audio_pattern)
        return other

    def render_text(self, on="#", off="."):
        """The screen as text; on xochip each pixel is its plane mask, "." for dark, "1", "2", "3"."""
        if self.platform == "chip8":
            return "\n".join("".join(on if p else off for p in row) for row in self.screen)
        if self.platform == "schip":
            return "\n".join("".join(on if p else off for p in row) for row in self.planes[0])
        return "\n".join("".join(".123"[a + 2 * b] for a, b in zip(r1, r2))
                         for r1, r2 in zip(*self.planes))


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
