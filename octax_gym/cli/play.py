"""`octax-gym play`: play a game in the browser, watch an agent, record your episodes (docs/play.md).

    octax-gym play Brix                               # prints http://127.0.0.1:PORT/
    octax-gym play Duel --players human,scripted --open
    octax-gym play Brix --agent runs/brix/params.msgpack
    octax-gym play Brix --record octax/Brix-human-v0 --recorder alice
    octax-gym play my_game.ch8                        # a ROM file: all 16 keys, no score

Needs the `play` extra (aiohttp): pip install 'octax-gym[play]'. The server and JAX are imported
only when the command runs.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
from pathlib import Path

from octax_gym.cli.common import GAME_OR_ROM_HELP, game_or_rom, help_of  # noqa: F401  (help_of: shared helpers)

PLAY_HINT = "pip install 'octax-gym[play]'"


def add_commands(commands: argparse._SubParsersAction) -> None:
    play = commands.add_parser(
        "play", help="play a game in your browser (a local web server; keys, agents, recording)",
        description="Starts a local web server where the env runs and prints its address: the page shows the "
                    "screen in the game's palette and takes the keyboard (Octo's layout: 1234/QWER/ASDF/ZXCV). "
                    "Needs the play extra: " + PLAY_HINT + ". See docs/play.md.")
    play.add_argument("game", metavar="GAME|ROM", help=GAME_OR_ROM_HELP + "; two-player games too (Duel)")
    play.add_argument("--port", type=int, default=0, metavar="N", help="port, 0..65535 (default 0: a free one)")
    play.add_argument("--host", default=None, metavar="H",
                      help="address to bind (default 127.0.0.1, this machine only; a loopback address keeps the "
                           "Host check against DNS rebinding; anything else is reachable by others on your "
                           "network and accepts any Host: a warning is printed)")
    play.add_argument("--open", action="store_true", help="open the page in the default browser")
    play.add_argument("--seed", type=int, default=0, metavar="S",
                      help="S in 0..4294967295; episode e is seeded (S + e) mod 2**32 (default 0)")
    play.add_argument("--agent", type=Path, metavar="PATH",
                      help="a trained agent: params.msgpack from the JAX examples, or a Stable-Baselines3 zip")
    play.add_argument("--trust-agent", action="store_true",
                      help="load an SB3 zip the player cannot rebuild as data with SB3's own loader, which runs "
                           "code stored in the file: only for files you trust (docs/play.md)")
    play.add_argument("--players", metavar="P[,P]",
                      help="who plays each seat: human, agent, scripted (two-player games), random "
                           "(default: human, and for two players the agent, else the scripted player)")
    play.add_argument("--record", metavar="DATASET_ID",
                      help="store your episodes as a Minari dataset (namespace/name-vN; the datasets extra)")
    play.add_argument("--recorder", default="human", metavar="NAME", help="who records, in the dataset's metadata")
    play.add_argument("--data-path", type=Path, metavar="DIR", help="write the dataset under DIR "
                                                                     "(default $MINARI_DATASETS_PATH or ~/.minari/datasets)")
    play.add_argument("--overwrite", action="store_true", help="replace a dataset of that id")
    play.add_argument("--max-episode-steps", type=int, metavar="M", help="truncate episodes after M steps")
    play.set_defaults(func=_cmd_play)


def _check_port_and_seed(args: argparse.Namespace) -> None:
    """Refuses, before anything is compiled, a port the socket and a seed the env would refuse later."""
    from octax_gym.step.compiled_step import MAX_SEED

    if not 0 <= args.port <= 65535:
        raise ValueError(f"--port must be in 0..65535 (0: a free port), got {args.port}")
    if not 0 <= args.seed < MAX_SEED:
        raise ValueError(f"--seed must be in 0..{MAX_SEED - 1} (the env's seeds are uint32; episode e is "
                         f"seeded (S + e) mod 2**32), got {args.seed}")


def _cmd_play(args: argparse.Namespace) -> int:
    _check_port_and_seed(args)
    try:
        import aiohttp  # noqa: F401
    except ImportError as exc:
        raise ImportError(f"octax-gym play needs aiohttp (the play extra): {PLAY_HINT} ({exc})") from exc
    from octax_gym.play.hosts import is_loopback
    from octax_gym.play.server import PlayServer
    from octax_gym.play.session import Session, is_two_player

    _log_octax_gym()
    if args.data_path is not None:
        os.environ["MINARI_DATASETS_PATH"] = str(args.data_path.expanduser().resolve())
    spec, rom = game_or_rom(args.game)
    two = is_two_player(spec)
    num_actions = len(spec.seats.action_keys[0] if two else spec.action_keys) + 1
    agent = None
    if args.agent is not None:
        from octax_gym.play.agents import load_agent
        agent = load_agent(args.agent, num_actions, trust=args.trust_agent, spec=spec)
    players = None if args.players is None else [p.strip() for p in args.players.split(",")]
    if players is not None and len(players) != (2 if two else 1):
        raise ValueError(f"--players takes {2 if two else 1} name(s) for {spec.id}, got {args.players!r}")
    env_options = {} if args.max_episode_steps is None else {"max_episode_steps": args.max_episode_steps}
    recorder = None
    if args.record is not None:
        if rom is not None:
            raise ValueError("--record stores a registered game's episodes (the dataset rebuilds its env by id); "
                             f"{rom} is a ROM file with no game spec")
        if two:
            raise ValueError("--record stores one-player games (the human's episodes of a one-player env); "
                             f"{spec.id} is a two-player game")
        from octax_gym.play.record import Recorder
        from octax_gym.envs.vector import OctaxVectorEnv
        probe = OctaxVectorEnv(spec.id, 1, **env_options)
        recorder = Recorder(spec.id, args.record, observation_space=probe.single_observation_space,
                            num_actions=num_actions, recorder=args.recorder, overwrite=args.overwrite,
                            env_options=env_options)
        probe.close()
    print(f"compiling {spec.id} ...", file=sys.stderr)
    if rom is not None:
        env_options["rom"] = rom
    session = Session(spec, seed=args.seed, agent=agent, players=players, recorder=recorder, **env_options)
    host = args.host or "127.0.0.1"
    if not is_loopback(host):  # the server then accepts any Host header: it must, to be reached by name
        print(f"octax-gym play: warning: binding {args.host}: anyone who can reach this address can play and "
              "see the game; the page has no login", file=sys.stderr)
    server = PlayServer(session, host=host)

    def started(url: str) -> None:
        print(f"octax-gym play: {spec.id} at {url}  (Ctrl-C to stop)", flush=True)
        if args.open:
            import webbrowser
            webbrowser.open(url)

    try:
        server.run(args.port, on_start=started)
    finally:
        session.close()
        if recorder is not None:
            recorder.close()
            print(f"recorded {recorder.episodes} episode(s), {recorder.steps} steps, as {recorder.dataset_id} "
                  f"at {recorder.path}")
    return 0


class _StderrHandler(logging.StreamHandler):
    """Writes to whatever `sys.stderr` is when a line is logged, not when the handler was made: the
    command can run more than once in a process (tests capture stderr anew each time), and a
    handler holding the first run's stream would write to a closed file."""

    @property
    def stream(self):
        return sys.stderr

    @stream.setter
    def stream(self, value):  # StreamHandler.__init__ assigns it; the property always answers sys.stderr
        pass


def _log_octax_gym() -> None:
    """The server's log lines (the `octax_gym` loggers, INFO and up) on stderr, and nobody else's:
    a root `logging.basicConfig(level=INFO)` would also print every library's INFO lines, JAX's
    "Unable to initialize backend 'tpu'" probe on each start among them."""
    logger = logging.getLogger("octax_gym")
    logger.setLevel(logging.INFO)
    if not any(getattr(handler, "octax_gym_play", False) for handler in logger.handlers):
        handler = _StderrHandler()
        handler.setFormatter(logging.Formatter("%(asctime)s %(name)s %(levelname)s %(message)s"))
        handler.octax_gym_play = True  # added once, however many times the command runs in a process
        logger.addHandler(handler)
