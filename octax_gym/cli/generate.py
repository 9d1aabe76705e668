"""`octax-gym generate`: games from a procedural family, checked and archived.

    octax-gym generate --list-families
    octax-gym generate --family dodger --count 64 --seed 0 --out generated/dodger
    octax-gym generate --llm-url http://127.0.0.1:8000/v1 --model M --description TEXT --count 4 --repairs 3 --out DIR

Writes each candidate's Octo source (NAME.8o) and ROM (NAME.ch8) into the folder, and
`archive.json`: every candidate with its parameters, hash, split, scores and, for a rejected
one, the reasons (`octax_core.generate.filters`). The same arguments write the same archive,
byte for byte. With --llm-url, the programs come from a language model through the paper's loop
(`octax_core.generate.llm`: the assembler's messages sent back up to --repairs times) and go
through the same checks. `octax_gym.generated.load_archive(DIR)` plays it. See docs/generate.md.
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
    llm = generate.add_argument_group("the LLM path (the paper's loop; in place of --family)")
    llm.add_argument("--llm-url", metavar="URL", help="an OpenAI-compatible API, e.g. http://127.0.0.1:8000/v1")
    llm.add_argument("--model", metavar="M", help="the model the server is asked for")
    llm.add_argument("--description", action="append", default=[], metavar="TEXT",
                     help="a game to write (repeatable; --count games cycle through the descriptions)")
    llm.add_argument("--descriptions", type=Path, metavar="FILE", help="descriptions, one a line")
    llm.add_argument("--repairs", type=int, default=3, metavar="K",
                     help="times a program that does not assemble goes back with the assembler's message (default 3)")
    llm.add_argument("--api-key-env", default="OPENAI_API_KEY", metavar="VAR",
                     help="the environment variable holding the API key (default OPENAI_API_KEY; unset: no key sent)")
    llm.add_argument("--prompt-part", action="append", default=[], metavar="NAME=PATH",
                     help="fill a part of the paper's prompt from a file: documentation, tutorial1, tutorial2 or example")
    llm.add_argument("--temperature", type=float, metavar="T", help="sampling temperature (default: the server's)")
    llm.add_argument("--trace-steps", type=int, default=1500, metavar="N",
                     help="steps the register tracer plays to check (or find) the score and end (default 1500)")
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
    if args.llm_url is not None:
        return _cmd_llm(args)
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


def _cmd_llm(args: argparse.Namespace) -> int:
    import os

    if args.family is not None:
        raise ValueError("give --family (a procedural family) or --llm-url (the LLM path), not both")
    descriptions = list(args.description)
    if args.descriptions is not None:
        try:
            text = args.descriptions.read_text(encoding="utf-8")
        except OSError as exc:
            raise ValueError(f"--descriptions: cannot read {args.descriptions}: {exc.strerror}") from None
        descriptions += [line.strip() for line in text.splitlines() if line.strip()]
    if args.model is None or args.out is None or not descriptions:
        raise ValueError("the LLM path needs --llm-url URL, --model M, --out DIR and --description TEXT "
                         "(or --descriptions FILE)")
    for name, low in (("count", 1), ("repairs", 0), ("trace_steps", 1)):
        if getattr(args, name) < low:
            raise ValueError(f"--{name.replace('_', '-')} must be >= {low}, got {getattr(args, name)}")
    paths = {}
    for item in args.prompt_part:
        name, sep, path = item.partition("=")
        if not sep or not path:
            raise ValueError(f"--prompt-part takes NAME=PATH, got {item!r}")
        paths[name] = path
    from octax_core.generate import chat, llm, prompt

    parts = prompt.read_parts(paths)
    chat.endpoint(args.llm_url)  # a bad URL is refused before any work
    key = os.environ.get(args.api_key_env) or None

    def ask(messages):
        return chat.complete(args.llm_url, args.model, messages, api_key=key, temperature=args.temperature)
    candidates = []
    for index in range(args.count):
        description = descriptions[index % len(descriptions)]
        candidate = llm.llm_candidate(ask, description, f"llm-{index:04d}", args.repairs, parts, model=args.model,
                                      trace_steps=args.trace_steps)
        print(f"{candidate.name}: {'assembled' if candidate.rom is not None else 'did not assemble'} after "
              f"{candidate.params['replies']} repl{'y' if candidate.params['replies'] == 1 else 'ies'}", flush=True)
        candidates.append(candidate)
    write_round(args.out, candidates, _settings(args),
                {"llm_url": args.llm_url, "model": args.model, "count": args.count, "repairs": args.repairs})
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
