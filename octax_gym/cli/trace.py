"""`octax-gym trace`: which registers hold the score, the lives, the game-over flag?

    octax-gym trace Brix --steps 2000                      with the game's reward and termination
    octax-gym trace Brix --blind --plot brix.png           told nothing, as for a raw ROM
    octax-gym trace my_game.ch8 --steps 4000 --csv ranking.csv

Plays the game with a random (or no-op) agent in a few envs (`octax_core.tools.trace.record_trace`),
ranks V0..VF per role (`octax_core.tools.trace_rank.rank_registers`) and prints the best candidates
with the evidence. A name that is not a game id is read as a ROM file with no spec
(`octax_gym.cli.common.game_or_rom`): all 16 keys, the platform's quirks (.sc8 SUPER-CHIP, .xo8
XO-CHIP, else CHIP-8), no start-up, no reward, episodes ending on a 2 s still screen. See docs/trace.md.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

from octax_gym.cli.common import GAME_OR_ROM_HELP, game_or_rom
from octax_gym.policies import POLICIES

MAX_PLOT_COLUMNS = 5  # --plot shows at most this many candidates per role
_ROLE_TITLES = {"score": "score", "lives": "lives", "game_over": "game over"}


def add_commands(commands: argparse._SubParsersAction) -> None:
    """Adds `trace` to the `octax-gym` parser."""
    trace = commands.add_parser(
        "trace", help="rank the registers that look like score, lives and game-over flags",
        description="Plays a game (or a raw ROM file) with a random or no-op agent, records V0..VF "
                    "every step and ranks them as score, lives and game-over candidates from their "
                    "trends, the ROM's code (FX33 etc.) and, for a registered game, its reward and "
                    "termination. See docs/trace.md.")
    trace.add_argument("game", metavar="GAME|ROM", help=GAME_OR_ROM_HELP)
    trace.add_argument("--steps", type=int, default=2000, metavar="N", help="env steps per env (default 2000)")
    trace.add_argument("--policy", choices=tuple(POLICIES), default="random",
                       help="random (default) or noop (no key ever held)")
    trace.add_argument("--envs", type=int, default=8, metavar="K", help="envs played side by side (default 8)")
    trace.add_argument("--seed", type=int, default=0, metavar="S", help="seeds the envs and the policy (default 0)")
    trace.add_argument("--top", type=int, default=3, metavar="K", help="candidates shown per role (default 3)")
    trace.add_argument("--blind", action="store_true",
                       help="a registered game: ignore its reward and termination, as for a raw ROM")
    trace.add_argument("--plot", type=Path, metavar="FILE.png",
                       help="also plot the top candidates' values over time in env 0, at most "
                            f"{MAX_PLOT_COLUMNS} per role (needs matplotlib)")
    trace.add_argument("--csv", type=Path, metavar="FILE.csv",
                       help="also write the full ranking: every register, every role")
    trace.set_defaults(func=_cmd_trace)


def _cmd_trace(args: argparse.Namespace) -> int:
    for name in ("steps", "envs", "top"):
        if getattr(args, name) < 1:
            raise ValueError(f"--{name} must be >= 1, got {getattr(args, name)}")
    if args.plot is not None:
        _check_plot_path(args.plot)
    from octax_core.tools.trace import record_trace
    from octax_core.tools.trace_rank import rank_registers

    spec, rom = game_or_rom(args.game)
    trace = record_trace(spec, steps=args.steps, num_envs=args.envs, policy=args.policy, seed=args.seed,
                         blind=args.blind, rom=rom)
    ranking = rank_registers(trace)
    print(_header(args, trace, raw=rom is not None))
    _print_ranking(ranking, args.top)
    if args.csv is not None:
        _write_csv(ranking, args.csv)
        print(f"wrote {args.csv}")
    if args.plot is not None:
        _plot(trace, ranking, args.top, args.plot)
        print(f"wrote {args.plot}")
    return 0


def _header(args: argparse.Namespace, trace, raw: bool) -> str:
    told = ("a raw ROM: all 16 keys, chip8 quirks, no start-up, no reward" if raw
            else "blind: the game's keys and start-up, no reward" if args.blind
            else "with the game's reward and termination")
    ends = int(trace.terminated.sum())
    how = f"screen still for {trace.stall_steps} steps" if trace.stall_steps else "the game's rule"
    return (f"{trace.game}: {args.steps} steps x {args.envs} envs, {args.policy} policy, seed {args.seed}; "
            f"{told}\n{ends} episodes ended ({how}), {int(trace.truncated.sum())} cut at the step limit\n")


def _print_ranking(ranking, top: int) -> None:
    from octax_core.tools.trace_rank import ROLES
    from octax_gym.cli.common import print_table

    rows = [("role", "rank", "register", "confidence", "reason")]
    for role in ROLES:
        shown = [c for c in ranking.top(role, top) if c.confidence > 0]
        rows += [(_ROLE_TITLES[role], str(i), c.name, f"{c.confidence:.2f}", c.reason)
                 for i, c in enumerate(shown, start=1)]
        if not shown:
            rows.append((_ROLE_TITLES[role], "-", "-", "0.00", "no register shows any evidence"))
    print_table(rows)
    for note in ranking.notes:
        print(f"note: {note}")


def _write_csv(ranking, path: Path) -> None:
    from octax_core.tools.trace_rank import ROLES

    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["role", "rank", "register", "confidence", "reason"])
        for role in ROLES:
            for i, c in enumerate(getattr(ranking, role), start=1):
                writer.writerow([role, i, c.name, f"{c.confidence:.4f}", c.reason])


def _check_plot_path(path: Path) -> None:
    if path.suffix.lower() != ".png":
        raise ValueError(f"--plot writes a PNG: the file name must end in .png, got {str(path)!r}")
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise ImportError("--plot needs matplotlib: pip install 'octax-gym[train]' (or pip install "
                          "matplotlib)") from None


def _plot(trace, ranking, top: int, path: Path) -> None:
    """A grid, one row per role and one panel per candidate (a score of 5 next to a counter of
    250 would be a flat line on a shared axis): its value in env 0, episode ends dotted."""
    from matplotlib.figure import Figure  # no pyplot: no GUI backend, no global state

    from octax_core.tools.trace_rank import ROLES

    columns = min(top, MAX_PLOT_COLUMNS)
    fig = Figure(figsize=(3.2 * columns + 1, 2.2 * len(ROLES) + 0.6), layout="constrained")
    axes = fig.subplots(len(ROLES), columns, sharex=True, squeeze=False)
    ends = trace.done[:, 0].nonzero()[0]
    for row, role in zip(axes, ROLES):
        for rank, (ax, c) in enumerate(zip(row, ranking.top(role, columns)), start=1):
            for t in ends:
                ax.axvline(t, color="0.6", linestyle=":", linewidth=0.8)
            ax.plot(trace.regs[:, 0, c.register], linewidth=1, drawstyle="steps-post")
            ax.set_title(f"{_ROLE_TITLES[role]} #{rank}: {c.name} ({c.confidence:.2f})", fontsize="medium")
    for ax in axes[-1]:
        ax.set_xlabel("env step (env 0)")
    fig.suptitle(f"{trace.game}: the top register candidates per role (dotted: an episode ended)")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
