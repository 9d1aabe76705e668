"""The filters: each check rejects the program it is for, all candidates of a round in one mix."""

import hashlib

import pytest

import octax_core.env.mix
from octax_core.generate import filters
from octax_core.generate.build import build_variant, variant_spec
from octax_core.generate.families import get_family
from octax_core.generate.sample import sample_params
from octax_core.tools.octo import assemble

HALTS = """
: main
	i := dot
	sprite v0 v0 1
	loop again
: dot 0b10000000
"""

RUNS_AWAY = """
: main
	i := dot
	sprite v0 v0 1
	jump 0x600
: dot 0b10000000
"""

UNKNOWN_OPCODE = """
: main
	i := dot
	sprite v0 v0 1
	loop
		v1 += 1
		0x5A 0x51
	again
: dot 0b10000000
"""

IGNORES_KEYS = """
: main
	i := dot
	loop
		sprite v0 v0 1
		v5 += 1
		v0 += 1
		if v5 == 60 then vE := 1
		if vE == 1 then jump over
	again
: over
	loop again
: dot 0b10000000
"""

SMALL = filters.Settings(frames=1200, end_limit=600, random_lanes=3, horizon=120, beam=6, repeat=4)


@pytest.fixture(scope="module")
def verdicts(monkeypatch_module):
    calls = []
    real = octax_core.env.mix.make_mix

    def counted(*args, **kwargs):
        calls.append(len(args[0]))
        return real(*args, **kwargs)
    monkeypatch_module.setattr(octax_core.env.mix, "make_mix", counted)
    family = get_family("dodger")
    good = build_variant(family, sample_params(family, 0, 42), "dodger-042")  # 1 thing, 1 life
    programs = {"good": good.rom, **{name: assemble(source) for name, source in
                                     (("halts", HALTS), ("runs_away", RUNS_AWAY), ("unknown", UNKNOWN_OPCODE),
                                      ("ignores_keys", IGNORES_KEYS))}}
    specs = [variant_spec(name, hashlib.sha1(rom).hexdigest()) for name, rom in programs.items()]
    result = dict(zip(programs, filters.check(specs, list(programs.values()), SMALL)))
    return result, calls


@pytest.fixture(scope="module")
def monkeypatch_module():
    with pytest.MonkeyPatch.context() as patch:
        yield patch


def test_one_mix_runs_the_whole_round(verdicts):
    assert verdicts[1] == [5]


def test_a_family_variant_passes(verdicts):
    good = verdicts[0]["good"]
    assert good.accepted, good.reasons
    assert good.reference_score >= good.random_horizon + filters.MARGIN


def test_a_halt_is_caught(verdicts):
    reasons = " | ".join(verdicts[0]["halts"].reasons)
    assert "halted (a jump to itself)" in reasons
    assert "keys change nothing" in reasons and "score never moves" in reasons
    assert "ends only 0% of episodes" in reasons


def test_leaving_the_program_is_caught(verdicts):
    assert "the program counter left the program" in verdicts[0]["runs_away"].reasons[0]


def test_an_unknown_opcode_is_caught(verdicts):
    assert "an unknown opcode" in verdicts[0]["unknown"].reasons[0]


def test_a_game_its_keys_do_not_touch_is_refused(verdicts):
    verdict = verdicts[0]["ignores_keys"]
    assert not any("faults" in reason for reason in verdict.reasons)
    assert "its keys change nothing on screen" in verdict.reasons
    assert any("reference search" in reason for reason in verdict.reasons)  # nothing to learn either
    # every line scores the same: 60 less the points the start-up counted before the episode began
    assert verdict.random_score == verdict.reference_score == verdict.random_horizon > 0


def test_known_words_follow_the_opcode_table():
    known = filters.known_words("chip8")
    assert known[0x00E0] and known[0xD015] and known[0x5A50]
    assert not known[0x5A51] and not known[0x00FF]  # 5XY1 is no opcode; 00FF is SUPER-CHIP's
    assert filters.known_words("schip")[0x00FF]
