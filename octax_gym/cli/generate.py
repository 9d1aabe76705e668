"""`octax-gym generate`: games from a procedural family, checked and archived.

    octax-gym generate --list-families
    octax-gym generate --family dodger --count 64 --seed 0 --out generated/dodger

Writes each candidate's Octo source (NAME.8o) and ROM (NAME.ch8) into the folder, and
`archive.json`: every candidate with its parameters, hash, split, scores and, for a rejected
one, the reasons (`octax_core.generate.filters`). The same arguments write the same archive,
byte for byte. `octax_gym.generated.load_archive(DIR)` plays it. See docs/generate.md.
"""

from __future__ import annotations

import argparse
from pathlib import Path


def add_commands(commands: argparse._SubParsersAction) -> None:
    """Adds `generate` to the `octax-gym` parser."""
    generate = commands.add_parser(
        "generate", help="games from a procedural family, checked and written to an archive",
        description="Samples variants of a procedural family (or, with --llm-url, asks a language "
                    "model for programs), checks every candidate in one batch (runs, draws, keys "
                    "matter, score moves, ends, a search beats random play) and writes the sources, "
                    "ROMs and DIR/archive.json. See docs/generate.md.")
    generate.add_argument("--list-families", action="store_true", help="print the families and exit")
    generate.add_argument("--family", metavar="F", help="the family to sample (see --list-families)")
    generate.add_argument("--count", type=int, default=16, metavar="N", help="candidates (default 16)")
    generate.add_argument("--seed", type=int, default=0, metavar="S", help="the sampling seed (default 0)")
    generate.add_argument("--out", type=Path, metavar="DIR", help="the folder to write (created)")
    checks = generate.add_argument_group("checks (left out: the archive's own, octax_core.generate.filters.Settings; "
                                         "smaller is quicker and looser)")
    for name, help_text in (("frames", "random-play frames each candidate must run without a fault (10000)"),
                            ("end-limit", "steps within which random play must end an episode (2000)"),
                            ("random-lanes", "random-play episodes per candidate (4)"),
                            ("horizon", "steps the reference search is compared with random play over (300)"),
                            ("beam", "the reference search's beam (16)")):
        checks.add_argument(f"--{name}", type=int, metavar="N", help=help_text)
    generate.set_defaults(func=_cmd_generate)


def _cmd_generate(args: argparse.Namespace) -> int:
    from octax_core.generate.families import FAMILIES

    if args.list_families:
        for family in FAMILIES.values():
            low, high = family.ranges[family.split]
            print(f"{family.name:8s} {family.description}")
            print(f"{'':8s} params: " + ", ".join(f"{k} {lo}..{hi}" for k, (lo, hi) in family.ranges.items())
                  + ", sprites: " + ", ".join(family.sprites)
                  + f"; test split: {family.split} in {list(family.held_out)} (of {low}..{high})")
        return 0
    if args.out is None or args.family is None:
        raise ValueError("generate needs --family F and --out DIR (or --list-families); families: "
                         + ", ".join(FAMILIES))
    if args.family not in FAMILIES:
        raise ValueError(f"unknown family {args.family!r}; valid: {', '.join(FAMILIES)}")
    for name in ("count", "frames", "end_limit", "random_lanes", "horizon", "beam"):
        if getattr(args, name) is not None and getattr(args, name) < 1:
            raise ValueError(f"--{name.replace('_', '-')} must be >= 1, got {getattr(args, name)}")
    if args.seed < 0:
        raise ValueError(f"--seed must be >= 0, got {args.seed}")
    from octax_core.generate import rounds

    candidates = rounds.family_candidates(FAMILIES[args.family], args.count, args.seed)
    write_round(args.out, candidates, _settings(args), {"family": args.family, "count": args.count, "seed": args.seed})
    return 0


def _settings(args: argparse.Namespace):
    from octax_core.generate.filters import Settings

    given = {name: getattr(args, name) for name in ("frames", "end_limit", "random_lanes", "horizon", "beam")}
    return Settings(seed=args.seed, **{name: value for name, value in given.items() if value is not None})


def write_round(out: Path, candidates, settings, run: dict) -> list[dict]:
    """Judges the candidates and writes their files and the archive; prints a summary."""
    from octax_core.generate import archive, rounds

    rows = rounds.judge(candidates, settings)
    out.mkdir(parents=True, exist_ok=True)
    for candidate in candidates:
        (out / f"{candidate.name}.8o").write_text(candidate.source, encoding="utf-8")
        if candidate.rom is not None:
            (out / f"{candidate.name}.ch8").write_bytes(candidate.rom)
    path = archive.write(out, rows, {**run, **rounds.settings_row(settings)})
    accepted = [row for row in rows if row["accepted"]]
    print(f"{len(accepted)} of {len(rows)} accepted ({sum(r['split'] == 'test' for r in accepted)} in the test split); "
          f"wrote {path}")
    for row in rows:
        if not row["accepted"]:
            print(f"  rejected {row['name']}: {'; '.join(row['reasons'])}")
    return rows
