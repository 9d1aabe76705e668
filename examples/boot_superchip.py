"""Boot a SUPER-CHIP (or XO-CHIP) program and print its 128x64 screen as text.

    python examples/boot_superchip.py                    # a tiny program written here: big "8", scrolled
    python examples/boot_superchip.py GAME.ch8 xochip    # any ROM, platform schip (default) or xochip

The Chip8 Community Archive's SUPER-CHIP and XO-CHIP games run this way; they ship in the package
(`octax_core.env.romstore.ARCHIVE_ROM_DIR`: e.g. blackrainbow.ch8 schip, civiliz8n.ch8 xochip),
and each wants its own quirks and tick rate, which the programs.json beside them lists
(`octax_core.emulator.quirks.quirks_from_octo` reads its flags).
"""

import sys

import jax

import octax_core

# hires; VA = 8; i := bighex VA; V0, V1 = 48, 16; draw the 8x10 digit at (48, 16); scroll down 4; loop
TINY = bytes.fromhex("00FF" "6A08" "FA30" "6030" "6110" "D01A" "00C4" "120E")

rom = sys.argv[1] if len(sys.argv) > 1 else TINY
platform = sys.argv[2] if len(sys.argv) > 2 else "schip"
machine = octax_core.Machine(platform, instructions_per_frame=30)  # the platform's own quirks
state = jax.jit(machine.run_frames, static_argnums=2)(machine.boot(rom, jax.random.key(0)), 0, 60)
print(octax_core.render_text(state))
snap = octax_core.snapshot(state)
print(f"{platform}: screen {snap['screen'].shape}, hires {bool(snap['hires'])}, exited {bool(snap['exited'])}, "
      f"lit pixels {int(snap['screen'].sum())}")
