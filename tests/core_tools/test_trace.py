"""`octax_core.tools.trace` (recording) and `octax_core.tools.trace_rank` (ranking).

The ranking is checked on hand-made traces whose answer is known (a rare +1 score, a lives count
that ends the episode at 0, a game-over flag, next to a clock, a timer, a random walk and noise),
then on short traces of real games. Real traces share one compile per (game, mode, shape).
"""

from __future__ import annotations

import dataclasses
import hashlib

import numpy as np
import pytest

import octax_core
from octax_core.tools.rom_scan import reachable_code, rom_facts
from octax_core.tools.trace import DEFAULT_STALL_STEPS, Trace, blind_spec, raw_rom_spec, record_trace
from octax_core.tools.trace_rank import ROLES, ended_rows, rank_registers

JUMP_TO_SELF = bytes.fromhex("1200")  # a ROM with no static hint at all
SCORE, LIVES, FLAG, CLOCK, TIMER, WALK, NOISE = 3, 9, 12, 1, 2, 4, 7
START_LIVES = 3


def _synthetic(steps=600, envs=4, seed=0, rom=JUMP_TO_SELF, reward_register=None) -> Trace:
    """N envs of a made-up game: V3 rises by 1 on ~5% of steps, V9 (lives, from 3) falls by 1 on
    ~2% and the episode ends when it reaches 0, VC is 1 on that last step only; V1 is a clock
    (+1 every step), V2 a timer (-1 every step from 60), V4 a random walk, V7 noise."""
    rng = np.random.default_rng(seed)
    reset = np.zeros(16, np.uint8)
    reset[[LIVES, TIMER]] = START_LIVES, 60
    regs = np.zeros((steps, envs, 16), np.uint8)
    terminated = np.zeros((steps, envs), bool)
    for n in range(envs):
        v = reset.astype(int).copy()
        for t in range(steps):
            v[SCORE] += rng.random() < 0.05
            v[LIVES] -= rng.random() < 0.02
            v[CLOCK] = (v[CLOCK] + 1) % 256
            v[TIMER] = v[TIMER] - 1 if v[TIMER] > 0 else 60
            v[WALK] = np.clip(v[WALK] + rng.choice([-1, 1]), 0, 63)
            v[NOISE] = rng.integers(256)
            v[FLAG] = v[LIVES] == 0
            regs[t, n] = v
            terminated[t, n] = v[LIVES] == 0
            if terminated[t, n]:
                v = reset.astype(int).copy()
    reward = np.zeros((steps, envs), np.float32)
    trace = Trace(game="synthetic", regs=regs, pc=np.full((steps, envs), 0x200, np.uint16), reward=reward,
                  terminated=terminated, truncated=np.zeros_like(terminated), reset_regs=reset, rom=rom,
                  has_reward=reward_register is not None)
    if reward_register is not None:
        deltas = trace.deltas[..., reward_register].astype(np.float32)
        trace = dataclasses.replace(trace, reward=deltas)
    return trace


def _top(ranking, role, k=1) -> list[int]:
    return [c.register for c in ranking.top(role, k)]


# --- the ranking, on traces whose answer is known -----------------------------------------------


def test_synthetic_roles_are_found_from_the_trends_alone():
    trace = _synthetic()
    assert trace.terminated.sum() >= 6, "the made-up game should end a few episodes"
    ranking = rank_registers(trace)
    assert _top(ranking, "score") == [SCORE]
    assert _top(ranking, "lives") == [LIVES]
    # the flag and the lives count at 0 both mark exactly the ended steps
    assert set(_top(ranking, "game_over", 2)) == {FLAG, LIVES}
    assert "no reward" in " ".join(ranking.notes)
    by_register = {c.register: c for c in ranking.score}
    assert by_register[SCORE].confidence > 2 * max(by_register[CLOCK].confidence, by_register[WALK].confidence)
    assert "rises on" in by_register[SCORE].reason


def test_every_role_ranks_all_16_registers_best_first():
    ranking = rank_registers(_synthetic())
    for role in ROLES:
        candidates = getattr(ranking, role)
        assert sorted(c.register for c in candidates) == list(range(16))
        confidences = [c.confidence for c in candidates]
        assert confidences == sorted(confidences, reverse=True)
        assert all(0.0 <= c <= 1.0 for c in confidences)
    assert ranking.top("score", 2)[0].name == f"V{SCORE:X}"
    with pytest.raises(ValueError, match="unknown role 'points'.*score, lives, game_over"):
        ranking.top("points")


def test_a_reward_overrides_the_trends():
    # The reward follows the random walk: with a reward, the register that moves with it is the score.
    ranking = rank_registers(_synthetic(reward_register=WALK))
    assert _top(ranking, "score") == [WALK]
    assert "moves with the reward (r=+1.00)" in ranking.score[0].reason
    assert not any("no reward" in note for note in ranking.notes)


def test_bcd_in_the_rom_decides_when_nothing_moves():
    # Tetris under random play: the score never changes, but the ROM shows VA with FX33.
    trace = _synthetic(rom=bytes.fromhex("FA33" "1202"))
    still = dataclasses.replace(trace, regs=np.zeros_like(trace.regs), reset_regs=np.zeros(16, np.uint8),
                                terminated=np.zeros_like(trace.terminated))
    ranking = rank_registers(still)
    assert _top(ranking, "score") == [0xA]
    assert ranking.score[0].reason == "shown by FX33"
    assert all(c.confidence == 0 for c in ranking.game_over)
    assert any("no episode ended" in note for note in ranking.notes)


def test_rom_lives_hints_break_a_tie_between_two_identical_counters():
    trace = _synthetic(rom=bytes.fromhex("75FF" "3500" "1204"))  # V5 -= 1; skip if V5 == 0
    twin = trace.regs.copy()
    twin[..., 5] = twin[..., LIVES]
    reset = trace.reset_regs.copy()
    reset[5] = START_LIVES
    ranking = rank_registers(dataclasses.replace(trace, regs=twin, reset_regs=reset))
    assert _top(ranking, "lives") == [5]
    assert "ROM: ADD -1, tested for 0" in ranking.lives[0].reason


def test_a_constant_register_is_no_game_over_flag_even_when_episodes_are_very_short():
    # Cavern4 under random play: every other step ends an episode, so `V6 == 9`, true everywhere,
    # would have an F1 of 0.67 with the ended steps. It tells nothing and must score 0.
    terminated = np.zeros((40, 2), bool)
    terminated[1::2] = True
    regs = np.zeros((40, 2, 16), np.uint8)
    regs[..., 6] = 9
    regs[..., 14] = np.where(terminated, 0, 1)  # the flag: 1 while playing, 0 when it ends
    reset = np.zeros(16, np.uint8)
    reset[[6, 14]] = 9, 1
    trace = dataclasses.replace(_synthetic(steps=40, envs=2), regs=regs, terminated=terminated, reset_regs=reset)
    ranking = rank_registers(trace)
    assert _top(ranking, "game_over") == [14]
    assert "VE == 0 at 100% of ended steps, 0.0% of others" == ranking.game_over[0].reason
    assert {c.register: c.confidence for c in ranking.game_over}[6] == 0.0


def test_deltas_restart_from_the_reset_registers_after_an_episode_end():
    trace = _synthetic(steps=50, envs=1)
    regs = trace.regs.astype(int)
    deltas = trace.deltas
    assert deltas.dtype == np.int16 and deltas.shape == regs.shape
    assert np.array_equal(deltas[0], regs[0] - trace.reset_regs)
    ends = np.nonzero(trace.done[:-1, 0])[0]
    for t in range(1, 50):
        before = trace.reset_regs.astype(int) if t - 1 in ends else regs[t - 1]
        assert np.array_equal(deltas[t], regs[t] - before)


def test_ended_rows_cover_the_whole_stall_window():
    trace = _synthetic(steps=12, envs=1)
    terminated = np.zeros((12, 1), bool)
    terminated[6] = terminated[11] = True
    stalled = dataclasses.replace(trace, terminated=terminated, stall_steps=3)
    assert np.nonzero(ended_rows(stalled)[:, 0])[0].tolist() == [4, 5, 6, 9, 10, 11]
    by_rule = dataclasses.replace(stalled, stall_steps=0)
    assert np.nonzero(ended_rows(by_rule)[:, 0])[0].tolist() == [6, 11]


# --- static analysis ----------------------------------------------------------------------------


def test_reachable_code_follows_jumps_calls_and_skips_and_never_decodes_data():
    rom = bytes.fromhex(
        "1203"  # 200: jump 203 (odd: a data byte sits between)
        "AA"  # 202: data
        "2209"  # 203: call 209
        "4300"  # 205: skip next if V3 != 0
        "120F"  # 207: jump 20F (end)
        "8410"  # 209: V4 := V1
        "F433"  # 20B: bcd V4 (shows V1 too)
        "00EE"  # 20D: return
        "12FF"  # 20F: jump away (out of the ROM)
        "F733"  # 211: never reached: data that looks like bcd V7
    )
    code = reachable_code(rom)
    assert code == [0x200, 0x203, 0x205, 0x207, 0x209, 0x20B, 0x20D, 0x20F]
    facts = rom_facts(rom)
    assert np.nonzero(facts.bcd)[0].tolist() == [1, 4]
    assert np.nonzero(facts.tested_zero)[0].tolist() == [3]
    assert not facts.decremented.any() and not facts.digit.any()


# --- recording real games ----------------------------------------------------------------------


@pytest.fixture(scope="module")
def brix_trace(octax_rom_dir) -> Trace:
    return record_trace("Brix", steps=300, num_envs=4, seed=0)


def test_a_trace_has_the_documented_shapes_and_dtypes(brix_trace):
    t = brix_trace
    assert t.game == "Brix" and t.has_reward and t.stall_steps == 0
    assert t.regs.shape == (300, 4, 16) and t.regs.dtype == np.uint8
    assert t.pc.shape == (300, 4) and t.pc.dtype == np.uint16
    for name in ("reward", "terminated", "truncated"):
        assert getattr(t, name).shape == (300, 4)
    assert t.reward.dtype == np.float32 and t.terminated.dtype == bool
    assert t.reset_regs.shape == (16,) and t.reset_regs[14] == 5  # Brix starts with 5 balls
    assert hashlib.sha1(t.rom).hexdigest() == octax_core.get_spec("Brix").rom_sha1


def test_brix_registers_match_the_paper(brix_trace):
    # Episodes end at the first lost ball (the paper's rule), so the reward and ends are there.
    assert brix_trace.terminated.sum() >= 4
    # The reward is the change of V5, and an episode ends on the row where V14 reads 4.
    assert np.array_equal(brix_trace.reward, brix_trace.deltas[..., 5])
    assert np.all(brix_trace.regs[brix_trace.terminated][:, 14] == 4)
    ranking = rank_registers(brix_trace)
    assert _top(ranking, "score") == [5] and _top(ranking, "lives") == [14] and _top(ranking, "game_over") == [14]


def test_same_seed_same_trace_and_env_rows_do_not_depend_on_the_batch(brix_trace, octax_rom_dir):
    again = record_trace("Brix", steps=300, num_envs=4, seed=0)
    for name in ("regs", "pc", "reward", "terminated", "truncated"):
        assert np.array_equal(getattr(again, name), getattr(brix_trace, name)), name
    fewer = record_trace("Brix", steps=300, num_envs=2, seed=0)
    assert np.array_equal(fewer.regs, brix_trace.regs[:, :2])
    other = record_trace("Brix", steps=300, num_envs=4, seed=1)
    assert not np.array_equal(other.regs, brix_trace.regs)


def test_blind_brix_ends_on_the_halt_and_still_finds_score_and_lives(octax_rom_dir):
    trace = record_trace("Brix", steps=1000, num_envs=4, seed=0, blind=True)
    assert not trace.has_reward and trace.stall_steps == DEFAULT_STALL_STEPS
    assert not trace.reward.any()
    assert trace.terminated.any(), "the ROM halts after the 5th ball: a stall"
    assert np.all(trace.regs[trace.terminated][:, 14] == 0)  # every stall came with no balls left
    ranking = rank_registers(trace)
    assert _top(ranking, "score") == [5] and _top(ranking, "lives") == [14] and _top(ranking, "game_over") == [14]


def test_a_raw_rom_file_is_traced_with_all_keys_and_no_reward(tmp_path):
    from counter_game import COUNTER_ROM  # V0 counts up while key 1 or 2 is held

    path = tmp_path / "counter.ch8"
    path.write_bytes(COUNTER_ROM)
    spec = raw_rom_spec(path)
    assert spec.id == "counter.ch8" and spec.action_keys == tuple(range(16))
    assert spec.rom_sha1 == hashlib.sha1(COUNTER_ROM).hexdigest()
    trace = record_trace(spec, steps=200, num_envs=2, rom=path)
    assert not trace.has_reward and not trace.reward.any() and not trace.done.any()
    assert _top(rank_registers(trace), "score") == [0]


def test_noop_policy_holds_no_key(tmp_path):
    from counter_game import COUNTER_ROM

    path = tmp_path / "counter.ch8"
    path.write_bytes(COUNTER_ROM)
    trace = record_trace(raw_rom_spec(path), steps=200, num_envs=2, rom=path, policy="noop", stall_steps=0)
    assert not trace.regs[..., 0].any()  # V0 only counts while a key is held


def test_blind_spec_keeps_keys_and_startup_but_drops_the_signals():
    spec = octax_core.get_spec("Brix")
    blind = blind_spec(spec)
    assert (blind.action_keys, blind.startup, blind.quirks) == (spec.action_keys, spec.startup, spec.quirks)
    assert blind.lives_fn is None and blind_spec(spec) == blind  # equal specs: one compile


@pytest.mark.parametrize("kwargs, message", [
    ({"steps": 0}, "steps must be an int >= 1, got 0"),
    ({"steps": 10, "num_envs": 0}, "num_envs must be an int >= 1, got 0"),
    ({"steps": 10, "policy": "greedy"}, "unknown policy 'greedy'; valid: random, noop"),
    ({"steps": 10, "stall_steps": -1}, "stall_steps must be an int >= 0"),
])
def test_bad_arguments_name_the_problem(kwargs, message):
    with pytest.raises(ValueError, match=message):
        record_trace("Brix", **kwargs)


def test_unknown_game_and_bad_rom_files_are_refused(tmp_path):
    with pytest.raises(KeyError, match=r"unknown game 'Nope' \(see octax_core.list_games\(\)"):
        record_trace("Nope", steps=10)
    with pytest.raises(FileNotFoundError, match="no ROM file at"):
        raw_rom_spec(tmp_path / "missing.ch8")
    (tmp_path / "empty.ch8").write_bytes(b"")
    with pytest.raises(ValueError, match="is empty"):
        raw_rom_spec(tmp_path / "empty.ch8")


# --- the suite: a longer check, blind -------------------------------------------------------------

# Paper games whose score the ROM shows with FX33 and a random agent moves: told nothing,
# the top score candidate must still be the paper's register (docs/trace.md has every game).
BLIND_SCORE = {"Brix": 5, "Deep8": 9, "Filter": 14, "Missile": 7, "Rocket": 1, "Submarine": 7, "UFO": 7,
               "VerticalBrix": 8, "WipeOff": 6}


@pytest.mark.slow
@pytest.mark.parametrize("game, register", sorted(BLIND_SCORE.items()))
def test_blind_top_score_candidate_is_the_papers_register(game, register, octax_rom_dir):
    ranking = rank_registers(record_trace(game, steps=1000, num_envs=8, seed=0, blind=True))
    assert _top(ranking, "score") == [register], [(c.name, round(c.confidence, 2), c.reason) for c in ranking.score[:3]]
