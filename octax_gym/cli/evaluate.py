"""`octax-gym evaluate`: an agent of a two-player game against the game's ladder of fixed opponents.

    octax-gym evaluate Cycles --agent runs/selfplay/agents/Cycles-seed0.msgpack --opponents ladder --episodes 64
    octax-gym evaluate octax/Duel-v1 --agent scripted --opponents ladder --episodes 64 --json
    octax-gym evaluate Cycles --agent eps0.1 --opponents random,scripted --episodes 32

The agent is a saved agent file (`octax-gym train selfplay`'s `agents/<game>-seed<s>.msgpack`,
read by `octax_gym.jax_policy`), played greedily (its largest legal logit) unless `--sampled`,
or a player of the core's table (`octax_core.env.players`: random, noop, scripted, eps<p>). It
plays `--episodes` games against each opponent, half from each seat, each to its end or
`--max-steps`, in one compiled match (`octax_core.env.ladder`). Against the ladder (random,
eps0.5, eps0.25, eps0.1, scripted) the rungs also play each other, which rates them (Bradley-Terry,
random at Elo 0), and the agent's Elo is fitted against those ratings held fixed.

Greedy is the default because a sampled policy keeps its exploration: issue 41 measured a
self-play policy at 1.06 nats of entropy on Cycles, about a quarter of its moves random, and at
10% random moves even the scripted Cycles player wins none of 32 games against itself.

An agent trained with mirrored seats (`octax-gym train selfplay --mirror`: its file says so, see
`octax_gym.jax_policy`) is played in the mirrored env it trained in, so from seat 1 it sees the
mirror image; the table's players there answer in the mirror image too, which for them is the
same game.

`--json` prints one object: {"game", "agent", "policy", "mirror", "episodes", "max_steps", "rungs": [{"opponent",
"win", "draw", "loss", "margin", "ended", "episodes", "by_seat"}, ...], "elo", "ladder": {rung: Elo}}; win,
draw and loss are fractions of the episodes, margin the mean of the agent's return minus the
opponent's, by_seat the same four from each seat (a game whose seats differ, Paddles, shows which
seat can be beaten).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any, Optional

LADDER = "ladder"


def add_commands(commands: argparse._SubParsersAction) -> None:
    """Adds `evaluate` to the `octax-gym` parser."""
    evaluate = commands.add_parser(
        "evaluate", help="an agent of a two-player game against the ladder of fixed opponents: win rates, Elo",
        description="Plays an agent (a saved agent file, or a player: random, noop, scripted, eps<p>) against "
                    "each opponent of a two-player game, half the episodes from each seat, and prints its win, "
                    "draw and loss rates, its mean margin and, against the ladder, its Elo (random = 0). "
                    "See docs/multiplayer.md.")
    evaluate.add_argument("game", metavar="GAME", help="a two-player game id (Cycles) or Gymnasium id (octax/Duel-v1)")
    evaluate.add_argument("--agent", required=True, metavar="A",
                          help="a saved agent file (.msgpack, octax-gym train selfplay's) or a player name: random, "
                               "noop, scripted, eps<p> (the scripted player, a random action with probability p)")
    evaluate.add_argument("--opponents", default=LADDER, metavar="ladder|NAME[,NAME]",
                          help="ladder (default: random, eps0.5, eps0.25, eps0.1, scripted, and the Elo) or "
                               "player names")
    evaluate.add_argument("--episodes", type=int, default=64, metavar="N",
                          help="games per opponent, an even number: half from each seat (default 64)")
    evaluate.add_argument("--max-steps", type=int, default=None, metavar="M",
                          help="steps per game at most (default: the game's max_episode_steps)")
    evaluate.add_argument("--sampled", action="store_true",
                          help="sample the agent file's actions from its policy (default: greedy, the largest logit)")
    evaluate.add_argument("--seed", type=int, default=0, metavar="S", help="seeds the starts and the draws (default 0)")
    evaluate.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    evaluate.set_defaults(func=_cmd_evaluate)


def _cmd_evaluate(args: argparse.Namespace) -> int:
    result = evaluate(args.game, args.agent, opponents=args.opponents, episodes=args.episodes,
                      max_steps=args.max_steps, sampled=args.sampled, seed=args.seed)
    if args.json:
        print(json.dumps(result))
    else:
        print(format_result(result))
    return 0


def evaluate(game: Any, agent: str, *, opponents: str = LADDER, episodes: int = 64, max_steps: Optional[int] = None,
             sampled: bool = False, seed: int = 0, rom=None) -> dict:
    """The agent's record against each opponent (see the module docstring for the result).

    Args:
        game: a two-player game's id, Gymnasium id or `GameSpec` (with `rom=`, its ROM file).
        agent: a saved agent file's path or a player name.
        opponents: "ladder" or player names, comma-separated.

    Raises:
        UnknownOptionError: not a two-player game. ValueError: an agent that is neither a file nor
        a player, an unknown opponent, an odd episode count, a network of other planes or actions.
    """
    import jax

    from octax_core.env.ladder import play_ladder
    from octax_core.env.multi import make_multi
    from octax_core.validate import check_int
    from octax_gym.envs.game_names import resolve_spec

    spec = resolve_spec(game, players=2)
    episodes = check_int("--episodes", episodes, 2)
    if episodes % 2:
        raise ValueError(f"--episodes must be even (half the games from each seat), got {episodes}")
    saved = _saved_agent(agent)
    # An agent trained with --mirror sees seat 1 as the mirror image: it plays in a mirrored env,
    # where the ladder's scripted rungs answer in the mirror image too (the same game for them).
    mirror = saved is not None and saved[1].mirror
    env, params = make_multi(spec, rom=rom, mirror=mirror)
    if max_steps is None:
        max_steps = int(params.max_episode_steps)
    max_steps = check_int("--max-steps", max_steps, 1)
    names = None if opponents == LADDER else [name.strip() for name in str(opponents).split(",")]
    player, agent_params, label = agent_player(agent, env, greedy=not sampled, saved=saved)
    table = play_ladder(env, params, player, agent_params, jax.random.key(seed), num_games=episodes,
                        max_steps=max_steps, opponents=names, rate=names is None)
    return {"game": spec.id, "agent": label, "policy": "sampled" if sampled else "greedy", "mirror": mirror,
            "episodes": episodes, "max_steps": max_steps, **table}


def _saved_agent(agent: str):
    """(params, jax_policy.Network) of an agent file, or None for a player name."""
    if not Path(agent).is_file():
        return None
    from octax_gym.jax_policy import load_agent

    return load_agent(agent)


def agent_player(agent: str, env, greedy: bool = True, saved=None):
    """(player, params, label) of `--agent`: a table player (params None) or a saved network
    (`saved`: its `jax_policy.load_agent`, when already read).

    Raises:
        ValueError: neither a file nor a player name (the message names both kinds), or a network
            whose input planes or outputs do not fit the game.
    """
    from octax_core.env.players import check_player, make_player

    path = Path(agent)
    if path.is_file():
        return _network_player(path, env, greedy, saved)
    try:
        name = check_player(agent, env.spec)
    except ValueError as exc:
        raise ValueError(f"--agent {agent!r} is no file and no player: pass a saved agent file (.msgpack) or a "
                         f"player name ({exc})") from None
    return make_player(name, env.spec, env.mirrored), None, name


def _network_player(path: Path, env, greedy: bool, saved=None):
    """A saved network as a player (`jax_policy.network_player`), checked against the game's
    observation and actions. A one-player agent (no player plane) is fed the frames alone."""
    from octax_gym.jax_policy import load_agent, network_player

    params, network = saved if saved is not None else load_agent(path)
    if network.mirror and not env.mirrored:
        raise ValueError(f"{path} was trained with mirrored seats (--mirror): play it in a mirrored env "
                         f"(make_multi({env.spec.id!r}, mirror=True)), where seat 1 sees what it saw")
    planes = env.observation_shape[0]  # the frames and the player plane
    if network.channels not in (planes, planes - 1):
        raise ValueError(f"{path} reads {network.channels} planes; {env.spec.id}'s seats see {planes} (the frames "
                         f"and the player plane), so its agents read {planes} (or {planes - 1}: frames only)")
    if network.num_actions < env.num_actions:
        raise ValueError(f"{path} has {network.num_actions} outputs; {env.spec.id} has {env.num_actions} actions")
    return network_player(greedy, network.channels), params, str(path)


def format_result(result: dict) -> str:
    """The table `octax-gym evaluate` prints without --json."""
    seats = "mirrored seats: seat 1 sees the mirror image, " if result.get("mirror") else ""
    lines = [f"{result['game']}: {result['agent']} ({result['policy']}), {result['episodes']} episodes per "
             f"opponent ({seats}half from each seat), at most {result['max_steps']} steps each"]
    header = ("opponent", "win", "draw", "loss", "margin", "from seat 0 / 1", "ended")
    rows = [header] + [(row["opponent"], f"{row['win']:.2f}", f"{row['draw']:.2f}", f"{row['loss']:.2f}",
                        f"{row['margin']:+.2f}", " / ".join(f"{seat['margin']:+.2f}" for seat in row["by_seat"]),
                        f"{row['ended']:.2f}") for row in result["rungs"]]
    widths = [max(len(r[i]) for r in rows) for i in range(len(header))]
    lines += ["  ".join(cell.ljust(w) for cell, w in zip(r, widths)).rstrip() for r in rows]
    if result["elo"] is not None:
        ladder = ", ".join(f"{name} {elo:+.0f}" for name, elo in result["ladder"].items())
        lines.append(f"Elo {result['elo']:+.0f} against the ladder (Bradley-Terry, random = 0; the rungs: {ladder})")
    return "\n".join(lines)
