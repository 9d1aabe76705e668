"""`octax-gym record`: play a game with a random or no-op agent and write an H.264 mp4.

    octax-gym record Pong --steps 600 --out pong.mp4                   one env, 512 x 256
    octax-gym record Brix --steps 600 --out brix.mp4 --envs 4 --scale 4 --palette amber
    octax-gym record my_game.ch8 --steps 600 --out mine.mp4           a ROM file: 16 keys, no reward

A thin layer over `octax_gym.video.record`, which checks the arguments (its errors name the valid
choices) and is imported only when the command runs: it brings JAX and the emulator. A ROM file
(`octax_gym.cli.common.game_or_rom`) is registered with Gymnasium for the run (`register_game`),
so it records through the same vector env as a game.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from octax_gym.cli.common import GAME_OR_ROM_HELP, game_or_rom


def add_commands(commands: argparse._SubParsersAction) -> None:
    """Adds this module's subcommands to the `octax-gym` parser."""
    record = commands.add_parser(
        "record", help="play a game with a random or no-op agent and write an H.264 mp4",
        description="Plays N steps and writes the first screen plus one frame per step, at the "
                    "game's real speed (60 / frames_per_step fps). With --envs K > 1 each frame is a "
                    "grid of K games. Needs the video extra: pip install 'octax-gym[video]'. "
                    "See docs/video.md.")
    record.add_argument("game", metavar="GAME|ROM", help=GAME_OR_ROM_HELP + "; `octax-gym list` shows the games")
    record.add_argument("--steps", type=int, required=True, metavar="N",
                        help="env steps to play (the video has N + 1 frames)")
    record.add_argument("--out", type=Path, required=True, metavar="FILE.mp4", help="the video file to write")
    record.add_argument("--policy", default="random", metavar="random|noop",
                        help="random (default) or noop (action 0: no key held)")
    record.add_argument("--envs", type=int, default=1, metavar="K", help="games side by side in a grid (default 1)")
    record.add_argument("--seed", type=int, default=0, metavar="S",
                        help="seeds the games (env i: S + i) and the random policy")
    record.add_argument("--scale", type=int, metavar="R",
                        help="pixels per screen pixel (default 8: 512 x 256 per CHIP-8 game, "
                             "1024 x 512 per SUPER-CHIP or XO-CHIP one)")
    record.add_argument("--palette", metavar="NAME", help="white (default), octo, green, amber or blue")
    record.add_argument("--no-progress", action="store_true", help="no progress bar")
    record.set_defaults(func=_cmd_record)


def _cmd_record(args: argparse.Namespace) -> int:
    from octax_gym import video
    from octax_gym.envs.registration import register_game

    env_kwargs = {name: value for name, value in (("render_scale", args.scale), ("palette", args.palette))
                  if value is not None}
    game, rom = game_or_rom(args.game)
    if rom is not None:
        register_game(game, rom)  # its own Gymnasium id, for this process: video.record makes it by that id
    result = video.record(game, args.out, steps=args.steps, policy=args.policy, num_envs=args.envs,
                          seed=args.seed, progress=not args.no_progress, **env_kwargs)
    print(f"wrote {result.path}: {result.frames} frames, {result.width}x{result.height} at "
          f"{result.fps:g} fps ({result.seconds:.1f} s), {result.episodes} episode(s) ended")
    return 0
