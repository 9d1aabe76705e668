"""Prints the suite results of docs/trace.md: `OCTAX_ROM_DIR=../shared/roms/octax python docs/trace_table.py`.

For every registered game, `octax_core.tools.trace` plays 2000 steps x 8 envs with a random agent
in three modes and `octax_core.tools.trace_rank` ranks the registers; each table compares the top 3
candidates of one role with the registers the paper's appendix names.

- spec: the registered game, with its reward and termination (the reward is the score register's
  change, so the score column mostly checks the plumbing);
- blind: the game's keys, quirks and start-up, but no reward and no termination;
- raw: the bare ROM file, as `octax-gym trace FILE.ch8` sees it (16 keys, chip8 quirks, no start-up).

It takes about 10 minutes on 2 CPU cores (each game and mode compiles once). Options:
`--games Brix,Pong` for a few games, `--steps`, `--envs`, `--seed`.
"""

from __future__ import annotations

import argparse
import re

import octax_core
from octax_core.env import romstore
from octax_core.tools.trace import raw_rom_spec, record_trace
from octax_core.tools.trace_rank import ROLES, rank_registers

MODES = ("spec", "blind", "raw")
# The paper's registers (appendix, Game List), per game family (levels share them). Lives: the
# count of lives, balls or shots the paper names, or the spec's lives_fn (Airplane's targets
# left, Spacejam's ship flag). Game over: the registers the paper's termination rule reads.
REFERENCE = {
    #                score       lives    game over
    "Airplane":     ((11, 12),   (11,),   (11, 12)),
    "Blinky":       ((6,),       (),      (3,)),
    "Brix":         ((5,),       (14,),   (14,)),
    "Cavern":       ((0,),       (),      (14,)),
    "Deep8":        ((9,),       (),      (11,)),
    "Filter":       ((14,),      (13,),   (13,)),
    "FlightRunner": ((7,),       (),      (5, 7)),
    "Missile":      ((7,),       (6,),    (6,)),
    "Pong":         ((14,),      (),      (14,)),
    "Rocket":       ((1,),       (),      (2,)),
    "ShootingStars": ((0,),      (),      ()),
    "SpaceFlight":  ((0,),       (9,),    (9, 12)),
    "Spacejam":     ((9,),       (10,),   (10,)),
    "Squash":       ((11,),      (11,),   (11,)),
    "Submarine":    ((7,),       (8,),    (8,)),
    "Tank":         ((14,),      (6,),    (6,)),
    "TargetShooter": ((2,),      (),      (3,)),
    "Tetris":       ((10,),      (),      (1,)),
    "UFO":          ((7,),       (8,),    (8,)),
    "VerticalBrix": ((8,),       (7,),    (7,)),
    "WipeOff":      ((6,),       (7,),    (7,)),
    "Worm":         ((5,),       (),      (7,)),
}
TITLES = {"score": "Score", "lives": "Lives", "game_over": "Game over"}


def reference(game_id: str):
    """The paper's (score, lives, game-over) registers for a game or its level; None if not a paper game."""
    return REFERENCE.get(re.sub(r"\d+$", "", game_id)) or REFERENCE.get(game_id)


def rankings(game_id: str, steps: int, envs: int, seed: int) -> dict:
    """mode -> (Ranking, episodes ended) for one game; raises the ROM store's errors."""
    spec = octax_core.get_spec(game_id)
    out = {}
    for mode in MODES:
        if mode == "raw":
            path = romstore.find_rom(spec)
            trace = record_trace(raw_rom_spec(path), steps=steps, num_envs=envs, seed=seed, rom=path)
        else:
            trace = record_trace(spec, steps=steps, num_envs=envs, seed=seed, blind=mode == "blind")
        out[mode] = (rank_registers(trace), int(trace.terminated.sum()))
    return out


def cell(ranking, ended: int, role: str, want: tuple[int, ...]) -> tuple[str, int]:
    """The top-3 registers, the reference ones in bold; and the rank of the first hit (0: none)."""
    top = [c for c in getattr(ranking, role) if c.confidence > 0]
    if role == "game_over" and not ended:
        return "no end seen", 0
    if not top:
        return "no evidence", 0
    names = [f"**{c.name}**" if c.register in want else c.name for c in top[:3]]
    rank = next((i for i, c in enumerate(top, start=1) if c.register in want), 0)
    return " ".join(names), rank


def tables(games: list[str], steps: int, envs: int, seed: int) -> str:
    results = {}
    for game_id in games:
        try:
            results[game_id] = rankings(game_id, steps, envs, seed)
        except (romstore.RomNotFoundError, romstore.RomHashError) as exc:
            results[game_id] = str(exc).splitlines()[0]
    return "\n\n".join(_role_table(role, results) for role in ROLES)


def _role_table(role: str, results: dict) -> str:
    index = ROLES.index(role)
    lines = [f"#### {TITLES[role]}", "",
             "| game | paper | " + " | ".join(MODES) + " |", "|---|---|" + "---|" * len(MODES)]
    hits = {mode: [0, 0] for mode in MODES}
    counted = 0
    for game_id, result in results.items():
        ref = reference(game_id)
        want = ref[index] if ref else ()
        paper = " ".join(f"V{k:X}" for k in want) if ref else "(not in the paper)"
        if isinstance(result, str):
            lines.append(f"| {game_id} | {paper or '-'} | " + " | ".join(["ROM missing"] * len(MODES)) + " |")
            continue
        cells = []
        for mode in MODES:
            text, rank = cell(*result[mode], role, want)
            cells.append(text)
            hits[mode][0] += rank == 1
            hits[mode][1] += 1 <= rank <= 3
        counted += bool(want)  # a game with no reference register has rank 0 everywhere
        lines.append(f"| {game_id} | {paper or '-'} | " + " | ".join(cells) + " |")
    lines.append("| **hits** (top-1 / top-3) | " + f"{counted} games | "
                 + " | ".join(f"{h1} / {h3}" for h1, h3 in hits.values()) + " |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description="Prints docs/trace.md's suite tables (markdown).")
    parser.add_argument("--games", help="comma-separated game ids (default: every registered game)")
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--envs", type=int, default=8)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    games = args.games.split(",") if args.games else octax_core.list_games()
    print(f"<!-- python docs/trace_table.py --steps {args.steps} --envs {args.envs} --seed {args.seed} -->")
    print(tables(games, args.steps, args.envs, args.seed))


if __name__ == "__main__":
    main()
