"""Measures every game's random and reference score: `python docs/scores.py [--games ID ...]`.

Writes octax_gym/data/scores.json (read at run time by `octax_gym.scores`, whose
`normalized_score` divides by reference - random) and docs/scores.md (the same table, and how
each column was measured). A run measures the games named with `--games` (every registered game
when none is named), keeps the others' saved rows, and rewrites both files; `--page-only`
rewrites them from the saved rows alone.

Random score: a uniform-random policy in `EPISODES` envs side by side, from `make(id)` defaults
(no autoreset), each env playing one episode from its own key of `jax.random.split(key(SEED))`
to its end (terminated, or truncated at the game's max_episode_steps); the action at step t
comes from `fold_in(episode key, t)`, so the result does not depend on how the steps are chunked.
The two slowest games get a step cap instead (`RANDOM_STEP_CAP`): their episodes are cut there,
the row says how many were, and such a game gets no normalized score.

Reference score: the best of what has been shown to be reachable, never a guess:

* "search": a beam search over the emulator's states, run here. The env is functional, so a
  state can be copied and stepped under every action: from `SEARCH_STARTS` reset keys, the
  search keeps `beam` states, steps each under every action held for `SEARCH_REPEAT` env steps,
  and keeps the best `beam` of the children, ranked by return so far, then lives left, with
  episodes that have ended ranked last and duplicate states (same registers, memory, screen,
  return) dropped. Holding actions for a few steps matters: a paddle that must cross the screen
  in time is out of reach of a beam that may change its mind every step (Brix, 4 starts at
  beam 11: 3 bricks on average at one step a choice, 20 at five). Its
  value per start is the best return of an episode that ended or reached the search's horizon;
  the reference is their mean over the starts. The search plays with the emulator as a perfect
  model, the game's random draws to come included, so it can do better than any policy that
  only sees the screen: an upper reach, not a policy's score. For that reason it is not run on
  the games of chance (`CHANCE_GAMES`), whose every policy scores about what random play does.
  Its size (starts, beam, horizon) follows a per-game budget of env steps (`search_settings`).
* "scripted": the scripted policies of docs/games.md (Dodge and Flak, which read the registers).
* "trained": the best PPO evaluation of docs/results.md (Airplane, Deep8, Dodge, Flak).

The reference is the highest of these; a game whose reference does not beat its random mean has
none, and so no normalized score. Where the rules give a maximum (`MAXIMA`, from each game's
module docstring) it is listed beside, and no reference may exceed it.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "octax_gym" / "data" / "scores.json"
PAGE = ROOT / "docs" / "scores.md"

SEED = 0  # the random policy's episode keys: jax.random.split(jax.random.key(SEED), EPISODES)
EPISODES = 32
CHUNK = 50  # env steps per jitted call; a run stops between calls once every episode has ended
# Random play is cut at this many steps where the whole episodes would take too long on the 2-core
# machine (about 55 and 130 env steps a second at 32 envs, 1,000 XO-CHIP instructions a frame).
RANDOM_STEP_CAP = {"OctoPartyMix": 200, "IntoTheGarlicScape": 300}

SEARCH_SEED = 1  # the search's start keys: jax.random.split(jax.random.key(SEARCH_SEED), SEARCH_STARTS)
SEARCH_STARTS = 2
SEARCH_REPEAT = 5  # env steps an action is held for between two choices of the search
MAX_BEAM, MIN_BEAM = 32, 4
# Env steps the search may play per game (starts x beam x actions x horizon): about 10 s of a
# CHIP-8 game at 11 instructions a frame here; the slower games get budgets from their speed in
# docs/speed.md (env steps/s at N=64 with skip_idle), for about a minute or two each.
SEARCH_BUDGET = 600_000
SLOW_SEARCH_BUDGET = {
    "BlackRainbow": 360_000, "Sens8tion": 360_000, "Rockto": 360_000, "Snake": 360_000, "FlutterBy": 360_000,
    "Piper": 400_000, "SpacejamArchive": 400_000,
    "SuperOctogon": 150_000, "Danm8ku": 150_000, "Sw8Copter": 150_000, "DodgeArchive": 200_000,
    "Civiliz8n": 80_000,
    "OctoPartyMix": 0, "IntoTheGarlicScape": 0,  # ~100 env steps/s: no search fits
}
CHANCE_GAMES = {
    "RPS": "a game of chance: every throw wins with chance 1/3 whatever the policy (its module docstring)",
    "SpockPaperScissors": "a game of chance: every policy's expected return is about 0 (its module docstring)",
}

# Returns documented elsewhere in the repository, each with where it comes from.
SCRIPTED = {  # docs/games.md: scripted policies reading the registers, 32 episodes
    **{game: (value, "scripted policy of docs/games.md (mean of 32 episodes)")
       for game, value in {"Dodge1": 187, "Dodge2": 177, "Dodge": 177, "Dodge3": 179,
                           "Flak1": 200, "Flak2": 200, "Flak": 200, "Flak3": 200}.items()},
}
TRAINED = {  # docs/results.md: PPO evaluations (mean return of the stochastic policy)
    "Airplane": (4.00, "pure-JAX PPO, 655k steps, 128 eval episodes (docs/results.md)"),
    "Deep8": (4.00, "pure-JAX PPO, 655k steps, 128 eval episodes (docs/results.md)"),
    "Dodge": (103.8, "pure-JAX PPO, 328k steps, 64 eval episodes cut at 1,500 steps (docs/results.md)"),
    "Flak": (50.5, "pure-JAX PPO, 328k steps, 64 eval episodes cut at 1,500 steps (docs/results.md)"),
}
NOTES = {  # what a reader of a row should know, shown under the table
    "Squash": "the reference is a stall: after a miss the ROM waits for a key to be pressed and released "
              "before it serves again (its module docstring), so a policy that holds a key loses no more "
              "balls and returns 0; the search found that, not good play.",
    "TargetShooter3": "the search scored 10 on one start, though the module docstring says the best score of "
                      "levels 2 and 3 is 9 (the ROM ends the game before the 10th target can be shot); "
                      "so no maximum is listed for those levels.",
    "Sens8tion": "random play already scores the maximum, 136 (every kill of the story, in every episode), so no "
                 "return can beat it; the search (beam 4, the budget of a SUPER-CHIP game with 9 actions) "
                 "stopped scoring after the first battle's 32 kills.",
}
MAXIMA = {  # the highest return the rules allow, from each game's module docstring
    "Brix": 96, "Filter": 99, "Missile": 40, "Pong": 9, "Rocket": 8, "WipeOff": 112, "TargetShooter1": 10,
    "Sens8tion": 136,
    # Not TargetShooter2 and 3: their docstring gives 9, but the search scored 10 on TargetShooter3.
    "Cavern1": 52, **{f"Cavern{n}": 63 for n in range(2, 8)},
    **{f"SpaceFlight{n}": 30 for n in range(1, 11)},
    **{game: 200 for game in ("Dodge", "Dodge1", "Dodge2", "Dodge3", "Flak", "Flak1", "Flak2", "Flak3")},
}


def _play_chunk(env, params, episode_keys):
    """A jitted call: CHUNK uniform-random steps of every env from step t0; returns summed."""
    import jax
    import jax.numpy as jnp

    def chunk(states, returns, t0):
        def body(carry, t):
            states, returns = carry
            step_keys = jax.vmap(jax.random.fold_in, in_axes=(0, None))(episode_keys, t)
            action_keys, env_keys = jnp.moveaxis(jax.vmap(jax.random.split)(step_keys), 1, 0)
            actions = jax.vmap(lambda k: jax.random.randint(k, (), 0, env.num_actions))(action_keys)
            _, states, reward, *_ = jax.vmap(env.step, in_axes=(0, 0, 0, None))(env_keys, states, actions, params)
            return (states, returns + reward), None
        return jax.lax.scan(body, (states, returns), t0 + jnp.arange(CHUNK))[0]
    return jax.jit(chunk)


def random_score(game_id: str, episodes: int = EPISODES, seed: int = SEED, step_cap=None) -> dict:
    """Uniform-random play, one episode per env: mean and std of the returns, and how they ended.

    `step_cap` cuts episodes shorter than the game's max_episode_steps (the env truncates there);
    `cut` counts the episodes it cut, which a full measurement leaves at 0.
    """
    import jax
    import jax.numpy as jnp
    import numpy as np

    import octax_core

    game_max = octax_core.get_spec(game_id).max_episode_steps
    limit = game_max if step_cap is None else min(step_cap, game_max)
    env, params = octax_core.make(game_id, max_episode_steps=limit)
    episode_keys = jax.random.split(jax.random.key(seed), episodes)
    _, states = jax.vmap(env.reset, in_axes=(0, None))(episode_keys, params)
    returns = jnp.zeros(episodes, jnp.float32)
    chunk = _play_chunk(env, params, episode_keys)
    started, t = time.perf_counter(), 0
    while t < limit and not bool(states.done.all()):
        states, returns = chunk(states, returns, t)
        t += CHUNK
    returns, lengths = np.asarray(returns, np.float64), np.asarray(states.episode_step)
    cut = int(np.sum(lengths >= limit)) if limit < game_max else 0
    return {"mean": float(returns.mean()), "std": float(returns.std()), "episodes": episodes,
            "ended": int(np.sum(np.asarray(states.done))) - cut, "cut": cut, "step_cap": limit,
            "mean_length": round(float(lengths.mean()), 1), "seconds": round(time.perf_counter() - started, 1)}


def search_settings(game_id: str):
    """(starts, beam, horizon, repeat) for the game's budget, or None where no search is run.

    The beam is the budget's share per action and start over the whole episode, at most
    MAX_BEAM; where that share falls under MIN_BEAM the horizon is shortened instead.
    """
    import octax_core

    budget = SLOW_SEARCH_BUDGET.get(game_id, SEARCH_BUDGET)
    if game_id in CHANCE_GAMES or budget == 0:
        return None
    spec = octax_core.get_spec(game_id)
    per_step = SEARCH_STARTS * (len(spec.action_keys) + 1)
    horizon = spec.max_episode_steps
    beam = min(MAX_BEAM, budget // (per_step * horizon))
    if beam < MIN_BEAM:
        beam, horizon = MIN_BEAM, budget // (per_step * MIN_BEAM)
    return SEARCH_STARTS, int(beam), int(horizon), SEARCH_REPEAT


def _state_hash(machine, weights):
    """A 32-bit hash of every machine field, to drop duplicate children from the beam."""
    import jax
    import jax.numpy as jnp

    flat = jnp.concatenate([jnp.ravel(leaf).astype(jnp.uint32) for leaf in jax.tree.leaves(machine)])
    return jnp.sum(flat * weights, dtype=jnp.uint32)


def beam_search(game_id: str, starts: int, beam: int, horizon: int, repeat: int, seed: int = SEARCH_SEED) -> dict:
    """The best return found per start (see the module docstring), with what the search cost."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    import octax_core

    env, params = octax_core.make(game_id, max_episode_steps=horizon)
    num_actions = env.num_actions
    _, first = jax.vmap(env.reset, in_axes=(0, None))(jax.random.split(jax.random.key(seed), starts), params)
    size = sum(int(np.prod(leaf.shape[1:])) for leaf in jax.tree.leaves(first.machine))
    weights = jnp.asarray(np.random.default_rng(seed).integers(1, 2**32, size, dtype=np.uint64) | 1, jnp.uint32)
    step_keys = jax.random.split(jax.random.key(0), beam * num_actions)  # draw sticky actions only: off

    def expand(states, returns):
        """One start: every beam state under every action, then the best `beam` children."""
        children = jax.tree.map(lambda x: jnp.repeat(x, num_actions, 0), states)
        actions = jnp.tile(jnp.arange(num_actions), beam)

        def hold(carry, _):  # the action held for `repeat` env steps
            children, reward, _ = carry
            _, children, step_reward, _, _, info = jax.vmap(env.step, in_axes=(0, 0, 0, None))(
                step_keys, children, actions, params)
            return (children, reward + step_reward, info["lives"]), None
        lives = jnp.zeros(beam * num_actions, jnp.int32)
        (children, reward, lives), _ = jax.lax.scan(hold, (children, jnp.zeros(beam * num_actions), lives), None,
                                                    length=repeat)
        child_returns = jnp.repeat(returns, num_actions) + reward
        ended_now = children.done & ~jnp.repeat(states.done, num_actions)
        best_ended = jnp.max(jnp.where(ended_now, child_returns, -jnp.inf))
        hashes = jax.vmap(_state_hash, in_axes=(0, None))(children.machine, weights)
        done = children.done.astype(jnp.int32)
        order = jnp.lexsort((hashes, -lives, -child_returns, done))  # the last key sorts first
        same = [x[order] for x in (hashes, lives, child_returns, done)]
        duplicate = jnp.concatenate([jnp.zeros(1, bool), jnp.all(jnp.stack([x[1:] == x[:-1] for x in same]), 0)])
        keep = order[jnp.argsort(duplicate, stable=True)][:beam]
        return jax.tree.map(lambda x: x[keep], children), child_returns[keep], best_ended

    @jax.jit
    def chunk(states, returns, best):
        def body(carry, _):
            states, returns, best = carry
            states, returns, best_ended = jax.vmap(expand)(states, returns)
            return (states, returns, jnp.maximum(best, best_ended)), None
        return jax.lax.scan(body, (states, returns, best), None, length=CHUNK // repeat)[0]

    states = jax.tree.map(lambda x: jnp.repeat(x[:, None], beam, 1), first)
    returns = jnp.zeros((starts, beam), jnp.float32)
    best = jnp.full((starts,), -jnp.inf, jnp.float32)
    started, t = time.perf_counter(), 0
    while t < horizon and not bool(states.done.all()):
        states, returns, best = chunk(states, returns, best)
        t += CHUNK
    at_horizon = jnp.max(jnp.where(states.done, -jnp.inf, returns), axis=1)
    found = np.maximum(np.asarray(best), np.asarray(at_horizon)).astype(np.float64)
    return {"starts": starts, "beam": beam, "horizon": horizon, "repeat": repeat, "returns": found.tolist(),
            "mean": float(found.mean()), "env_steps": int(min(t, horizon) * starts * beam * num_actions),
            "seconds": round(time.perf_counter() - started, 1)}


def reference(game_id: str, random: dict, search) -> dict:
    """The reference of one game from its measurements and the documented returns (module docstring)."""
    candidates = []
    if search is not None:
        detail = (f"beam search: {search['starts']} starts, beam {search['beam']}, actions held "
                  f"{search['repeat']} steps, horizon {search['horizon']} steps; best per start "
                  + ", ".join(f"{r:g}" for r in search["returns"]))
        candidates.append((search["mean"], "search", detail))
    for source, table in (("scripted", SCRIPTED), ("trained", TRAINED)):
        if game_id in table:
            candidates.append((float(table[game_id][0]), source, table[game_id][1]))
    best = max(candidates, default=None, key=lambda c: c[0])
    if random["cut"]:
        why = f"random play was cut at {random['step_cap']} steps ({random['cut']} of {random['episodes']} episodes)"
    elif game_id in CHANCE_GAMES:
        why = CHANCE_GAMES[game_id] + "; not searched"
    elif best is None:
        why = "no search fits the time budget and no other reference is documented"
    elif best[0] <= random["mean"]:
        why = f"no reference beats random (best: {best[0]:g}, {best[1]})"
    else:
        return {"reference": best[0], "reference_source": best[1], "reference_detail": best[2]}
    return {"reference": None, "reference_source": None, "reference_detail": why}


def measure(game_id: str) -> dict:
    """One game's measurements: its random play and its search."""
    from octax_core.env.games import suite_of

    random = random_score(game_id, step_cap=RANDOM_STEP_CAP.get(game_id))
    settings = search_settings(game_id)
    search = None if settings is None else beam_search(game_id, *settings)
    return {"suite": suite_of(game_id), "random": random, "search": search}


def finish(game_id: str, row: dict) -> dict:
    """The row with what follows from its measurements and the tables here: maximum, reference, note.

    Run on every row at every write, so that a change to SCRIPTED, TRAINED, MAXIMA or NOTES
    needs only `--page-only`.
    """
    row = {"suite": row["suite"], "random": row["random"], "search": row["search"], "maximum": MAXIMA.get(game_id)}
    row.update(reference(game_id, row["random"], row["search"]))
    if game_id in NOTES:
        row["note"] = NOTES[game_id]
    return row


# --- the page -------------------------------------------------------------------------------------


def _number(value) -> str:
    return "-" if value is None else f"{value:,.2f}".rstrip("0").rstrip(".")


def write_page(table: dict) -> str:
    rows = table["games"]
    with_reference = [g for g, row in rows.items() if row["reference"] is not None]
    sources = {}
    for game_id in with_reference:
        sources[rows[game_id]["reference_source"]] = sources.get(rows[game_id]["reference_source"], 0) + 1
    lines = [
        "# Random and reference scores",
        "",
        "Generated by `python docs/scores.py` (do not edit by hand); the same table ships as "
        "`octax_gym/data/scores.json`, which `octax_gym.scores` reads: `score_table()`, "
        "`normalized_score(game_id, score)` = (score - random) / (reference - random), and the "
        "aggregate statistics of Agarwal et al. (2021), \"Deep RL at the edge of the statistical "
        "precipice\": the interquartile mean (IQM) and stratified-bootstrap confidence intervals "
        "(`iqm`, `stratified_bootstrap_ci`, `aggregate`). Those are written on numpy: the "
        "authors' package, rliable (1.2.0, its last release, August 2024), no longer imports beside "
        "pandas 3 and arch 7.2 (`TypeError: deprecate_kwarg() missing 1 required positional argument`).",
        "",
        f"{len(rows)} games; {len(with_reference)} have a reference, and so a normalized score "
        f"({', '.join(f'{n} from {s}' for s, n in sorted(sources.items()))}).",
        "",
        "## How each column was measured",
        "",
        f"- **random**: a uniform-random policy, {table['episodes']} episodes side by side from "
        f"`jax.random.split(jax.random.key({table['seed']}), {table['episodes']})` (one episode per "
        "env, `make(id)` defaults: skip_idle on, no sticky actions, no no-op starts), each played to "
        "its end or the game's max_episode_steps; mean and standard deviation of the returns. "
        "`octax_gym/data/scores.json` also keeps the mean episode length. "
        f"{' and '.join(sorted(RANDOM_STEP_CAP))} run about 100 env steps a second here, so their random "
        "play is cut (the episodes column says where) and they get no normalized score.",
        f"- **reference**: the best return shown reachable, from one of: *search*, a beam search over "
        f"the emulator's states ({SEARCH_STARTS} starts from `jax.random.split(jax.random.key("
        f"{SEARCH_SEED}), {SEARCH_STARTS})`; every kept state stepped under every action held for "
        f"{SEARCH_REPEAT} env steps, the best "
        "`beam` children kept by return so far, then lives, episodes that ended last and duplicate "
        "states dropped; the best return of an episode that ended or reached the horizon, averaged "
        f"over the starts; beam and horizon from a budget of {SEARCH_BUDGET:,} env steps a game, less "
        "for the slow ones); *scripted*, the scripted policies of [games.md](games.md#our-own-games-dodge-and-flak); "
        "*trained*, the PPO evaluations of [results.md](results.md). The search plans with the "
        "emulator as a perfect model, future random draws included, so on games with chance it may "
        "reach what no policy that sees only the screen can: read its reference as an upper reach. "
        f"It is not run on the games of chance ({', '.join(sorted(CHANCE_GAMES))}). A reference that "
        "does not beat the random mean is dropped: that game has no normalized score (`-`).",
        "- **max**: the highest return the game's rules allow, where its module docstring gives one.",
        "",
        "Made on the development machine (x86_64, 2 CPU cores, no GPU, other jobs running beside) by:",
        "",
        *[f"    {run['command']}  # {run['games']} games, {run['wall_seconds'] / 60:.0f} minutes"
          for run in table["runs"]],
        "",
        "| game | suite | random (mean +- std) | episodes ended | reference | source | max | detail |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for game_id, row in rows.items():
        random = row["random"]
        ended = f"{random['ended']}/{random['episodes']}"
        if random["cut"]:
            ended += f" ({random['cut']} cut at {random['step_cap']})"
        lines.append(f"| {game_id} | {row['suite']} | {_number(random['mean'])} +- {_number(random['std'])} | "
                     f"{ended} | {_number(row['reference'])} | {row['reference_source'] or '-'} | "
                     f"{_number(row['maximum'])} | {row['reference_detail']} |")
    notes = [(game_id, row["note"]) for game_id, row in rows.items() if "note" in row]
    if notes:
        lines += ["", "## Notes", ""] + [f"- **{game_id}**: {note}" for game_id, note in notes]
    lines.append("")
    return "\n".join(lines)


def main(argv=None) -> int:
    import octax_core

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--games", nargs="*", default=None, help="measure only these games again")
    parser.add_argument("--page-only", action="store_true", help="rewrite both files from the saved rows")
    args = parser.parse_args(argv)
    games = octax_core.list_games()
    unknown = sorted(set(args.games or ()) - set(games))
    if unknown:
        parser.error(f"unknown games {unknown}")
    saved = json.loads(DATA.read_text()) if DATA.exists() else {"games": {}, "runs": []}
    rows = {g: row for g, row in saved["games"].items() if g in games}
    runs = list(saved.get("runs", []))
    todo = [] if args.page_only else (args.games or games)
    started = time.perf_counter()
    for game_id in todo:
        rows[game_id] = finish(game_id, measure(game_id))
        print(game_id, json.dumps(rows[game_id]), flush=True)
        _save(rows, runs)
    if todo:
        command = "python docs/scores.py" + (f" --games {' '.join(args.games)}" if args.games else "")
        runs = (runs if args.games else []) + [
            {"command": command, "games": len(todo), "wall_seconds": round(time.perf_counter() - started)}]
    missing = [g for g in games if g not in rows]
    if missing:
        print(f"not measured yet: {missing}", file=sys.stderr)
        return 1
    table = _save({g: finish(g, row) for g, row in rows.items()}, runs)
    PAGE.write_text(write_page(table))
    print(f"wrote {DATA.relative_to(ROOT)} and {PAGE.relative_to(ROOT)} ({len(rows)} games)")
    return 0


def _save(rows: dict, runs: list) -> dict:
    """Writes the package's table: the settings, the runs that made it, a row per game."""
    table = {"about": "random and reference scores per game; generated by docs/scores.py, see docs/scores.md",
             "seed": SEED, "episodes": EPISODES, "runs": runs, "games": {g: rows[g] for g in sorted(rows)}}
    DATA.parent.mkdir(exist_ok=True)
    DATA.write_text(json.dumps(table, indent=1) + "\n")
    return table


if __name__ == "__main__":
    raise SystemExit(main())
