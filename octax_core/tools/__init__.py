"""Tools for making and wrapping games: the Octo assembler and disassembler (`octo/`), and the
register tracer (`trace` records V0..VF under play, `trace_rank` ranks score, lives and game-over
candidates, `rom_scan` reads the ROM's reachable code). Built on the emulator and the env API.
"""
