"""`octax-gym asm` and `octax-gym disasm` (octax_gym/cli/octo.py), run in-process through `cli.main`."""

from __future__ import annotations

from octax_core.tools.octo import assemble
from octax_gym import cli

PROGRAM = """\
: main
  clear
  v0 := 1
  i := dot
  sprite v0 v0 1
  loop again
: dot 0x80
"""
PROGRAM_ROM = bytes.fromhex("00E0" "6001" "A20A" "D001" "1208" "80")


def test_asm_writes_the_rom_beside_the_source(tmp_path, capsys):
    source = tmp_path / "dot.8o"
    source.write_text(PROGRAM)
    assert cli.main(["asm", str(source)]) == 0
    assert (tmp_path / "dot.ch8").read_bytes() == PROGRAM_ROM
    assert capsys.readouterr().out == f"wrote 11 bytes to {tmp_path / 'dot.ch8'}\n"


def test_asm_output_option(tmp_path):
    source, rom = tmp_path / "dot.8o", tmp_path / "out" / "game.ch8"
    source.write_text(PROGRAM)
    rom.parent.mkdir()
    assert cli.main(["asm", str(source), "-o", str(rom)]) == 0
    assert rom.read_bytes() == PROGRAM_ROM


def test_asm_error_names_line_and_column_and_exits_1(tmp_path, capsys):
    source = tmp_path / "bad.8o"
    source.write_text(": main\n  v0 := 1\n  v1 += bogus\n")
    assert cli.main(["asm", str(source)]) == 1
    out, err = capsys.readouterr()
    assert out == ""
    assert err.startswith(f"octax-gym asm: error: {source}: line 3, column 9: ")
    assert "    v1 += bogus\n" in err and "\n            ^" in err  # the line, a caret under `bogus`
    assert not (tmp_path / "bad.ch8").exists()


def test_asm_refuses_to_overwrite_its_source(tmp_path, capsys):
    source = tmp_path / "dot.ch8"
    source.write_text(PROGRAM)
    assert cli.main(["asm", str(source)]) == 1
    assert "would overwrite the source" in capsys.readouterr().err
    assert source.read_text() == PROGRAM


def test_disasm_prints_source_that_reassembles(tmp_path, capsys):
    rom = tmp_path / "dot.ch8"
    rom.write_bytes(PROGRAM_ROM)
    assert cli.main(["disasm", str(rom)]) == 0
    source = capsys.readouterr().out
    assert "sprite v0 v0 1" in source
    assert assemble(source) == PROGRAM_ROM


def test_disasm_output_option_then_asm_gives_back_the_rom(tmp_path, capsys):
    rom, source, again = tmp_path / "dot.ch8", tmp_path / "dot.8o", tmp_path / "again.ch8"
    rom.write_bytes(PROGRAM_ROM)
    assert cli.main(["disasm", str(rom), "-o", str(source)]) == 0
    assert capsys.readouterr().out.startswith("wrote ")
    assert cli.main(["asm", str(source), "-o", str(again)]) == 0
    assert again.read_bytes() == PROGRAM_ROM


def test_disasm_of_a_missing_file_exits_1(tmp_path, capsys):
    assert cli.main(["disasm", str(tmp_path / "nope.ch8")]) == 1
    assert "no ROM file at" in capsys.readouterr().err
