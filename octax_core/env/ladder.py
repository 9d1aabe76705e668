"""The opponent ladder of a two-player game: fixed rungs, a compiled match, an Elo against the rungs.

    env, params = make_multi("Cycles")                              # autoreset=False: one game each
    match = make_match(env, params, num_games=64, max_steps=4500, players=[agent, *ladder_players(env.spec, env.mirrored)])
    result = match(0, agent_params, 1 + k, None, key)              # agent vs rung k, half from each seat
    table = play_ladder(env, params, agent, agent_params, key, num_games=64, max_steps=4500)

A self-play agent's returns against itself say nothing about how good it is (both seats improve
together); a fixed pool does: the rungs (`RUNGS`) are the table's players (`octax_core.env.players`)
from uniform random up to the game's scripted bot, with the scripted bot's actions diluted by
random ones in between, so that each rung beats the one below it (issue 41 measured 78-100% on
Cycles). The Elo (`bradley_terry_elo`) puts the rungs on one scale, anchored at "random" = 0, and
`elo_against` rates a player against those fixed ratings, so an agent's number does not move when
another agent is rated.

A match is a batch of games of a no-autoreset `MultiEnv`: A plays seat 0 in the first half and
seat 1 in the second (no seat's advantage reads as skill), B the other seat, each game to its end
or `max_steps`. A game is A's win when A's return (the change of its seat's score) is higher than
B's, a draw when equal: the same reading for zero-sum games (Duel: own points minus the other's)
and the others (SpaceRacer: each ship's crossings).
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple, Optional, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.env.games import GameSpec
from octax_core.env.multi import MultiEnv
from octax_core.env.players import Player, check_player, make_player, player_names
from octax_core.validate import check_int

RUNGS = ("random", "eps0.5", "eps0.25", "eps0.1", "scripted")  # weakest first
NO_SCRIPT_RUNGS = ("noop", "random")  # a game without a scripted player (SpaceRacer)
ANCHOR = "random"  # the rung at Elo 0
BT_ITERATIONS = 2000


def rungs(spec: GameSpec) -> tuple[str, ...]:
    """The game's rungs, weakest first: `RUNGS`, or `NO_SCRIPT_RUNGS` where it has no scripted player."""
    return RUNGS if "scripted" in player_names(spec) else NO_SCRIPT_RUNGS


def ladder_players(spec: GameSpec, mirrored: bool = False) -> list[Player]:
    """The rungs' players, in `rungs(spec)`'s order (`mirrored`: for an env made with `mirror=True`)."""
    return [make_player(name, spec, mirrored) for name in rungs(spec)]


class MatchResult(NamedTuple):
    """One match: each field (num_games,); A on seat 0 in the first half of the games."""

    return_a: np.ndarray  # float32: A's return
    return_b: np.ndarray  # float32: B's return
    ended: np.ndarray  # bool: the game reached its own end (terminated), not a step cap


def make_match(env: MultiEnv, env_params, num_games: int, max_steps: int,
               players: Sequence[Player]) -> Callable[..., MatchResult]:
    """`match(index_a, params_a, index_b, params_b, key) -> MatchResult`, jitted once for every
    pairing of `players` (each of the one signature, `octax_core.env.players`; `lax.switch` runs
    the two chosen): A is `players[index_a]` with `params_a`, B likewise. A network's params are an
    argument, so one compiled match plays every checkpoint; the table's players take any params
    (None). A plays seat 0 in the first half of the games and seat 1 in the second.

    Raises:
        ValueError: an env made with autoreset=True, an odd or non-positive `num_games`, a
            `max_steps` < 1, or no players.
    """
    if not isinstance(env, MultiEnv):
        raise ValueError(f"make_match needs a two-player env (octax_core.make_multi), got {type(env).__name__}")
    if env.config.autoreset:
        raise ValueError("make_match needs a MultiEnv made with autoreset=False (one game per env)")
    num_games = check_int("num_games", num_games, 2)
    if num_games % 2:
        raise ValueError(f"num_games must be even (half the games from each seat), got {num_games}")
    max_steps = check_int("max_steps", max_steps, 1)
    if not players:
        raise ValueError("make_match needs at least one player")
    v_reset = jax.vmap(env.reset, in_axes=(0, None))
    v_step = jax.vmap(env.step, in_axes=(0, 0, 0, None))
    legal_of = jax.vmap(env.legal_action_mask)
    a_seat = (jnp.arange(num_games) >= num_games // 2).astype(jnp.int32)
    b_seat = 1 - a_seat
    rows = jnp.arange(num_games)
    batched = [_batched(p) for p in players]

    def match(index_a, params_a, index_b, params_b, key):
        key, reset_key = jax.random.split(key)
        obs, state = v_reset(jax.random.split(reset_key, num_games), env_params)

        def running(carry):
            t, _, _, _, _, done, _ = carry
            return (t < max_steps) & ~done.all()

        def body(carry):
            t, key, obs, state, returns, done, ended = carry
            key, a_key, b_key, step_key = jax.random.split(key, 4)
            legal = legal_of(state)
            act_a = jax.lax.switch(index_a, batched, params_a, jax.random.split(a_key, num_games), obs[rows, a_seat],
                                   state, a_seat, legal[rows, a_seat])
            act_b = jax.lax.switch(index_b, batched, params_b, jax.random.split(b_key, num_games), obs[rows, b_seat],
                                   state, b_seat, legal[rows, b_seat])
            actions = jnp.where(a_seat[:, None] == jnp.arange(2)[None], act_a[:, None], act_b[:, None])
            obs, state, reward, terminated, truncated, _ = v_step(
                jax.random.split(step_key, num_games), state, actions, env_params)
            # An ended game stands still and pays 0 (no autoreset), so summing every step is safe.
            return t + 1, key, obs, state, returns + reward, done | terminated | truncated, ended | terminated

        no = jnp.zeros(num_games, jnp.bool_)
        carry = (jnp.int32(0), key, obs, state, jnp.zeros((num_games, 2), jnp.float32), no, no)
        _, _, _, _, returns, _, ended = jax.lax.while_loop(running, body, carry)
        return MatchResult(returns[rows, a_seat], returns[rows, b_seat], ended)

    compiled = jax.jit(match, compiler_options=env.compiler_options)  # the platform's (exact; faster)

    def play(index_a, params_a, index_b, params_b, key) -> MatchResult:
        for what, index in (("index_a", index_a), ("index_b", index_b)):
            check_int(what, index, 0, len(players) - 1)
        return MatchResult(*jax.device_get(compiled(jnp.int32(index_a), params_a, jnp.int32(index_b), params_b, key)))

    return play


def _batched(player: Player) -> Callable:
    """One player over a batch of games: params shared, everything else one row per game."""
    one = lambda *args: jnp.asarray(player(*args), jnp.int32)  # noqa: E731
    return jax.vmap(one, in_axes=(None, 0, 0, 0, 0, 0))


def record(result: MatchResult) -> dict[str, Any]:
    """A's record in a match: win, draw and loss rates, the mean margin (A's return - B's), the
    fraction of games that reached their own end (not a step cap: the match's or the env's
    truncation), the number of episodes, and "by_seat": win, draw, loss and margin of A's games
    from seat 0 (the first half) and from seat 1, for the games whose seats are not alike
    (Paddles' bottom paddle concedes nothing to the scripted top one)."""
    a, b = np.asarray(result.return_a, np.float64), np.asarray(result.return_b, np.float64)
    half = a.size // 2
    return {**_rates(a, b), "ended": float(np.asarray(result.ended).mean()), "episodes": int(a.size),
            "by_seat": [_rates(a[:half], b[:half]), _rates(a[half:], b[half:])]}


def _rates(a: np.ndarray, b: np.ndarray) -> dict[str, float]:
    return {"win": float((a > b).mean()), "draw": float((a == b).mean()), "loss": float((a < b).mean()),
            "margin": float((a - b).mean())}


def bradley_terry_elo(wins, games, anchor: int, iterations: int = BT_ITERATIONS) -> np.ndarray:
    """Elo ratings from a round robin: `wins[i, j]` is i's points against j (a win 1, a draw 0.5),
    `games[i, j]` their games. A Bradley-Terry model (P(i beats j) = p_i / (p_i + p_j)) fitted by
    maximum likelihood with Hunter's MM updates, one virtual draw added to every pair that played
    (a perfect record stays finite); returned as 400 log10(p), player `anchor` at 0.

    Raises:
        ValueError: shapes that differ or are not square, negative counts, or points above games.
    """
    wins, games = _with_virtual_draws(wins, games)
    if wins.ndim != 2 or wins.shape[0] != wins.shape[1]:
        raise ValueError(f"wins and games are square (players x players), got {wins.shape}")
    anchor = check_int("anchor", anchor, 0, len(wins) - 1)
    strength = np.ones(len(wins))
    for _ in range(iterations):
        denom = (games / (strength[:, None] + strength[None, :])).sum(1)
        new = np.where(denom > 0, wins.sum(1) / np.maximum(denom, 1e-300), strength)
        new /= np.exp(np.log(new).mean())
        done = np.allclose(new, strength, rtol=1e-10, atol=0)
        strength = new
        if done:
            break
    elo = 400 * np.log10(strength)
    return elo - elo[anchor]


def elo_against(pool_elo, wins, games, iterations: int = BT_ITERATIONS) -> float:
    """One player's Elo against a pool whose ratings stay fixed: `wins[j]` its points against pool
    player j, `games[j]` their games. The Bradley-Terry maximum likelihood for its strength alone
    (Hunter's MM update), one virtual draw per pool player it met; on `pool_elo`'s scale.

    Raises:
        ValueError: shapes that differ, no games, negative counts, or points above games.
    """
    pool_elo = np.asarray(pool_elo, np.float64)
    wins, games = _with_virtual_draws(wins, games)
    if wins.shape != pool_elo.shape:
        raise ValueError(f"one count per pool player: pool {pool_elo.shape}, wins {wins.shape}")
    if not games.sum():
        raise ValueError("elo_against needs at least one game against the pool")
    pool = 10 ** (pool_elo / 400)
    strength = 1.0
    for _ in range(iterations):
        new = wins.sum() / (games / (strength + pool)).sum()
        done = abs(new - strength) <= 1e-12 * strength
        strength = new
        if done:
            break
    return float(400 * np.log10(strength))


def _with_virtual_draws(wins, games) -> tuple[np.ndarray, np.ndarray]:
    wins, games = np.array(wins, np.float64), np.array(games, np.float64)
    if wins.shape != games.shape:
        raise ValueError(f"wins and games have one shape, got {wins.shape} and {games.shape}")
    if (wins < 0).any() or (wins > games).any():
        raise ValueError("points are between 0 and the games played")
    played = games > 0
    return wins + 0.5 * played, games + played


def play_ladder(env: MultiEnv, env_params, agent: Player, agent_params, key: jax.Array, *, num_games: int,
                max_steps: int, opponents: Optional[Sequence[str]] = None, rate: bool = True,
                match: Optional[Callable[..., MatchResult]] = None) -> dict[str, Any]:
    """`agent` (with `agent_params`) against each opponent (default: the game's rungs), and the
    rungs' round robin that rates them: returns {"rungs": one `record` per opponent, with its
    "opponent" name, "elo": the agent's Elo against the rungs, "ladder": the rungs' Elo}.

    The rungs' ratings come from their round robin (`num_games` a pair) in this run, anchored at
    "random"; the agent's Elo is fitted against them held fixed (`elo_against`) from its games
    against the rungs. `rate=False` skips the round robin ("elo" None, "ladder" empty). `match`: a
    match compiled by `make_match` for these players (`[agent, *ladder_players(spec)]`, then
    the other opponents), reused across calls. Every seat is passed `agent_params` (the table's
    players ignore them), so the match compiles once for one params structure.

    Raises:
        ValueError: an unknown opponent name (the message lists the valid ones).
    """
    spec = env.spec
    ladder = rungs(spec)
    opponents = ladder if opponents is None else tuple(check_player(name, spec) for name in opponents)
    extra = [name for name in opponents if name not in ladder]
    names = [*ladder, *extra]
    if match is None:
        match = make_match(env, env_params, num_games, max_steps,
                           [agent, *(make_player(name, spec, env.mirrored) for name in names)])
    index = {name: 1 + k for k, name in enumerate(names)}
    rows = []
    for k, name in enumerate(opponents):
        result = match(0, agent_params, index[name], agent_params, jax.random.fold_in(key, k))
        rows.append({"opponent": name, **record(result)})
    if not rate:
        return {"rungs": rows, "elo": None, "ladder": {}}
    count = len(ladder)
    points, games = np.zeros((count, count)), np.zeros((count, count))
    for i in range(count):
        for j in range(i + 1, count):
            result = match(index[ladder[i]], agent_params, index[ladder[j]], agent_params,
                           jax.random.fold_in(key, 1000 + i * count + j))
            score = record(result)
            points[i, j] = (score["win"] + 0.5 * score["draw"]) * score["episodes"]
            points[j, i] = score["episodes"] - points[i, j]
            games[i, j] = games[j, i] = score["episodes"]
    ladder_elo = bradley_terry_elo(points, games, ladder.index(ANCHOR) if ANCHOR in ladder else 0)
    against = {row["opponent"]: row for row in rows if row["opponent"] in ladder}
    agent_points = np.array([(against[n]["win"] + 0.5 * against[n]["draw"]) * against[n]["episodes"]
                             if n in against else 0.0 for n in ladder])
    agent_games = np.array([against[n]["episodes"] if n in against else 0 for n in ladder], np.float64)
    elo = elo_against(ladder_elo, agent_points, agent_games) if agent_games.sum() else None
    return {"rungs": rows, "elo": None if elo is None else round(elo, 1),
            "ladder": {name: round(float(e), 1) for name, e in zip(ladder, ladder_elo)}}
