"""`octax-gym list` and `octax-gym info GAME`: the registered games, read from their specs.

Nothing is emulated: both commands read `GameSpec`s, the `EnvConfig` defaults and the ROM store
(hashing the small ROM files), so they answer in about the time it takes to import JAX.

    octax-gym list [--category timing] [--suite ours]   every game: Gymnasium id, category, actions, ROM
    octax-gym info Pong                      one game in full (also `info octax/Pong-v0`)
    octax-gym info my_game.ch8               a ROM file: what it plays as (16 keys, no reward)
"""

from __future__ import annotations

import argparse
import sys
import textwrap

from octax_gym.cli.common import GAME_OR_ROM_HELP, game_or_rom

WIDTH = 100  # `info` wraps its text to this many columns

def add_commands(commands: argparse._SubParsersAction) -> None:
    """Adds `list` and `info` to the `octax-gym` parser."""
    games = commands.add_parser("list", help="every game: Gymnasium id, category, actions, ROM status",
                                description="A table of every registered game and whether its ROM is "
                                            "present and verified.")
    games.add_argument("--category", help="only this category (planning, timing, resources, "
                                          "navigation, reaction)")
    games.add_argument("--suite", help="only this suite (octax: the paper's games; ours: Dodge, Flak, Duel, Cycles)")
    games.set_defaults(func=_cmd_list)
    info = commands.add_parser("info", help="one game: actions, spaces, quirks, timers, ROM",
                               description="Everything a game's spec says, without running it.")
    info.add_argument("game", metavar="GAME|ROM", help=GAME_OR_ROM_HELP)
    info.set_defaults(func=_cmd_info)


def _cmd_list(args: argparse.Namespace) -> int:
    from octax_core.env import romstore
    from octax_core.env.games import CATEGORIES, SUITES, get_spec, list_games
    from octax_gym.envs.choices import UnknownOptionError
    from octax_gym.cli.common import print_table
    from octax_gym.envs.game_names import env_id

    problem = None
    if args.suite is not None and args.suite not in SUITES:
        problem = UnknownOptionError("suite", args.suite, SUITES)
    elif args.category is not None and args.category.lower() not in CATEGORIES:
        problem = UnknownOptionError("category", args.category, CATEGORIES)
    if problem is not None:
        print(f"octax-gym list: error: {problem}", file=sys.stderr)
        return 2  # a usage error, as argparse's own
    specs = [get_spec(game) for game in list_games(args.suite)]
    if args.category is not None:
        specs = [spec for spec in specs if spec.category == args.category.lower()]
    if not specs:
        print("no games registered" + (f" in category {args.category.lower()}" if args.category else ""))
        return 0
    table = [("gymnasium id", "category", "actions (keys)", "rom", "title")]
    statuses = romstore.rom_status(specs)
    for spec, status in zip(specs, statuses):
        table.append((env_id(spec.id), spec.category, f"{len(spec.action_keys) + 1} ({_keys(spec.action_keys)})",
                      _rom_word(status), spec.title))
    print_table(table)
    n_ok = sum(status.verified for status in statuses)
    print(f"\n{len(specs)} games, {n_ok} ROMs present and verified. Actions: 0 = no key, "
          "then the CHIP-8 keys (hex) in order; `octax-gym info GAME` for one game.")
    if n_ok < len(specs):
        print(f"To get the missing ROMs: {romstore.FIX_HINT}.")
    return 0


def _cmd_info(args: argparse.Namespace) -> int:
    from octax_core.env import romstore
    from octax_core.env.config import make_config
    from octax_core.emulator.platforms import resolve_platform
    from octax_core.emulator.state import screen_values_max, screen_values_shape
    from octax_core.emulator.quirks import resolve_quirks
    from octax_gym.envs import game_names

    spec, rom = game_or_rom(args.game)  # an unknown name: UnknownOptionError, exit status 1
    config = make_config(spec)[0]  # what gym.make / make_vec use by default (the game's own speed and timers)
    quirks = resolve_quirks(spec.quirks)
    platform = resolve_platform(spec.platform)
    screen = ", ".join(map(str, screen_values_shape(platform)))
    high = screen_values_max(platform, config.obs_scale)  # XO-CHIP: one value per plane combination
    status = romstore.rom_status([spec])[0] if rom is None else None
    frames, steps_per_second = config.frames_per_step, 60 / config.frames_per_step
    fields = [
        ("category", spec.category if rom is None else "none (a ROM file)"),
        ("description", spec.description),
        ("actions", f"Discrete({len(spec.action_keys) + 1}); action i holds its key for the whole step"),
        *[("", row) for row in _action_rows(spec.action_keys)],
        ("platform", spec.platform),
        ("observation", (f"Box(0, {high}, ({frames}, {screen}), uint8), the screen after each frame "
                         f"of the step; a vector env's is (num_envs, {frames}, {screen})")),
        ("step", (f"{frames} frames x {config.instructions_per_frame} instructions "
                  f"({steps_per_second:g} steps per second of game time)")),
        ("quirks", f"{spec.quirks if isinstance(spec.quirks, str) else 'custom'}: "
                   + ", ".join(f"{name}={value}" for name, value in vars(quirks).items())),
        ("timers", "frozen: delay and sound zeroed after every step (octax's disable_delay)"
                   if spec.freeze_timers else "real, 60 Hz (one tick a frame)"),
        ("max_episode_steps", f"{spec.max_episode_steps} (about {spec.max_episode_steps / steps_per_second:,.0f} s)"),
        ("startup", (", then ".join(_startup_step(mask, n) for mask, n in spec.startup) or "none")
                    + "; run once at make, every reset starts there"),
        ("lives", "yes: info['lives'] counts them" if spec.lives_fn is not None else "no: info['lives'] is -1"),
        ("rom", spec.rom_file if rom is None else str(rom)),
        ("rom sha1", spec.rom_sha1),
        ("rom status", _rom_word(status) + (f" at {status.path}" if status.path else "") if rom is None
                       else "a ROM file with no game spec: `octax-gym trace` ranks the registers that may hold "
                            "its score"),
    ]
    heading = (f"{game_names.env_id(spec)}, game id {spec.id!r}, version {spec.version}" if rom is None
               else f"the ROM file {str(rom)!r}")
    lines = [f"{spec.title}  ({heading})"]
    for name, text in fields:
        lines.append(textwrap.fill(text, WIDTH, initial_indent=f"{name + ':' if name else '':19}",
                                   subsequent_indent=" " * 19, break_on_hyphens=False))
    print("\n".join(lines))
    if status is not None and not status.verified:
        print(f"To fix: {romstore.FIX_HINT}.")
    return 0


def _action_rows(action_keys: tuple[int, ...]) -> list[str]:
    return ["0  no key"] + [f"{i}  CHIP-8 key {key:X}" for i, key in enumerate(action_keys, start=1)]


def _startup_step(mask: int, frames: int) -> str:
    held = [f"{key:X}" for key in range(16) if mask >> key & 1]
    return f"{frames} frame{'s' if frames != 1 else ''} " + (f"holding key {','.join(held)}" if held else "(no key)")


def _keys(action_keys: tuple[int, ...]) -> str:
    return ",".join(f"{key:X}" for key in action_keys)


def _rom_word(status) -> str:
    if status.verified:
        return "verified"
    return "missing" if status.path is None else "BAD SHA-1"
