"""Writes docs/gallery.md, the archive suite's page: `python docs/gallery.py [--only ID ...]`.

For each game of the "archive" suite (the Chip8 Community Archive's games, shipped in the
package): a strip of four frames of random play in the game's own colours (docs/gallery/<id>.png),
its platform, speed, keys, authors, what the reward counts (the first sentence of its module's
"### Reward" section), and what random play measured at N=64 envs on this machine: the mean
return and length of the episodes that ended, and env steps per second.

Measuring plays every game for a fixed budget of emulated instructions (about 10 s of this
machine's time per game), so a game at 1,000 instructions per frame plays far fewer steps than
one at 15; where no episode ended within its steps the page says so. Results are kept in
docs/gallery/measurements.json: a run measures only the games missing there (or those named with
`--only`), then rewrites the page from all of them. tests/core_games/test_archive_suite.py checks
that the page's table lists exactly the registry's archive games with their platform, speed, keys
and authors (`registry_rows` / `page_rows`).
"""

from __future__ import annotations

import argparse
import importlib
import json
import re
import sys
import time
from pathlib import Path

DOCS = Path(__file__).resolve().parent
FOLDER = DOCS / "gallery"
MEASUREMENTS = FOLDER / "measurements.json"
PAGE = DOCS / "gallery.md"
ARCHIVE_COMMIT = "0a41cc23ad5c"
SOURCE_URL = "https://github.com/JohnEarnest/chip8Archive/tree/{commit}/src/{name}"
NUM_ENVS = 64
# Emulated instructions per game for the measurement, and the steps' bounds: about 10 s here for a
# CHIP-8 game (its instructions are ~10x cheaper than SUPER-CHIP's and XO-CHIP's, see
# benchmarks/platforms.py), about 10-30 s for the others.
INSTRUCTION_BUDGET = {"chip8": 1.0e8, "schip": 1.2e7, "xochip": 6.0e6}
MIN_STEPS, MAX_STEPS = 50, 3000
PREVIEW_FRAMES = 4
SLOW_TICKRATE = 200  # games at this many instructions per frame or more are listed as slow
# Archive programs with no env, and why (titles as the archive gives them).
LEFT_OUT = (  # (archive program names, why): with the registered games, every program of the archive
    (tuple(f"octojam{n}title" for n in range(1, 11)), "title cards: greeting animations, nothing to play"),
    (("octopaint", "mondrian", "superOctoTrackXO"), "paint, composition and music tools"),
    (tuple(f"jub8-{n}" for n in range(1, 7)), "music"),
    (("8ceattourny_d1", "8ceattourny_d2", "8ceattourny_d3", "octoachip8story", "keshaWasBird", "keshaWasBiird",
      "expedition", "anEveningToDieFor", "DVN8"), "visual novels and stories: choices, no score"),
    (("applejak", "bulb", "squad"), "interpreters for programming languages"),
    (("1dcell", "chipquarium", "gradsim", "pumpkindressup", "petdog", "horseWorldOnline", "nokiatemplate"),
     "simulations, toys and templates: nothing to score"),
    (("eaty",), "the only number it keeps is a life force that drains with time: no score to reward"),
    (("octopeg",), "its end routine wipes the score within one step and it has no game over an env can "
                   "read reliably"),
    (("turnover77",), "no score and no randomness; its one goal, a maze's exit, we could not script to test"),
    (("chickenScratch",), "no way to lose and no score"),
    (("horseyJump",), "no game over: a fall just goes on"),
    (("chipwar",), "built by a 2014 Octo that relies on Octo's vfOrderQuirks (VF written before the result: its "
                   "`vf := 0; vf += vd` at 0x61B), which the core does not model: every move lands on the "
                   "wrong cell"),
    (("supersquare",), "its score never moved under random or scripted play in our trials"),
    (("tank", "ultimatetictactoe"), "two-player games with no one-player mode: TankArchive and UltimateTicTacToe "
                                    "are played by two (octax_core.make_multi, docs/multiplayer.md)"),
    (("dinorun", "down8"), "not yet: a lost game restarts on the same key that plays it (EX9E), so the end "
                           "must be caught before that key is read; to come"),
    (("BadKaiJuJu", "binding", "businessiscontagious", "chipcross", "glitchGhost", "keshaWasNiiinja", "knight",
      "octoma", "octorancher", "octovore", "ordinaryidlegarden", "redOctober", "sk8", "skyward", "sub8",
      "superneatboy", "t8nks", "tombstontipp", "trucksimul8or", "wonkypong"),
     "not yet: games whose keys, score and end are still to be read from their sources; to come "
     "(most run 200 to 10,000 instructions per frame, the next issue's work)"),
)
HEADER = ("| game | preview | platform, speed | keys | authors | reward | random return | episode length "
          "| steps/s (N=64) |\n|---|---|---|---|---|---|---|---|---|")


def _archive():
    import octax_core

    return octax_core, octax_core.list_games(suite="archive")


def program_name(spec) -> str:
    return spec.rom_file.removeprefix("archive/").removesuffix(".ch8")


def programs() -> dict:
    from octax_core.env.games.archive._program import programs as archive_programs

    return archive_programs()


def _keys(spec) -> str:
    return " ".join(f"{key:X}" for key in spec.action_keys)


def _authors(name: str) -> str:
    return ", ".join(programs()[name]["authors"])


def registry_rows() -> list[tuple[str, str, str, str]]:
    """(id, "platform, N ipf", keys, authors) per archive game, from the registry."""
    octax_core, games = _archive()
    rows = []
    for game_id in games:
        spec = octax_core.get_spec(game_id)
        rows.append((game_id, f"{spec.platform}, {spec.instructions_per_frame} ipf", _keys(spec),
                     _authors(program_name(spec))))
    return rows


def page_rows(page: str) -> list[tuple[str, str, str, str]]:
    """The same four columns, read back from the page's table."""
    rows = []
    for line in page.splitlines():
        match = re.match(r"\| \*\*(\w+)\*\* .*?\| .*? \| (\w+, \d+ ipf) \| ([0-9A-F ]+) \| (.*?) \|", line)
        if match:
            rows.append(match.groups())
    return rows


def game_modules() -> dict:
    """Archive game id -> the module that defines it (its docstring documents the game)."""
    import pkgutil

    import octax_core.env.games.archive as package

    modules = {}
    for info in pkgutil.iter_modules(package.__path__):
        if not info.name.startswith("_"):
            module = importlib.import_module(f"{package.__name__}.{info.name}")
            modules.update({spec.id: module for spec in module.SPECS})
    return modules


def reward_sentence(game_id: str) -> str:
    """The first sentence of the game module's '### Reward' section."""
    text = game_modules()[game_id].__doc__.split("### Reward", 1)[1].split("###", 1)[0]
    text = " ".join(text.split())
    sentence = re.split(r"(?<=[.:;])\s", text, maxsplit=1)[0].rstrip(".:;")
    return sentence.replace("|", "/")


def measure(game_id: str) -> dict:
    """Random play at N=64 for the game's instruction budget: returns, lengths, speed, preview."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    import octax_core
    from octax_gym.envs import render

    spec = octax_core.get_spec(game_id)
    env, params = octax_core.make(game_id, autoreset=True)
    per_step = NUM_ENVS * env.config.frames_per_step * env.config.instructions_per_frame
    steps = int(min(MAX_STEPS, max(MIN_STEPS, INSTRUCTION_BUDGET[spec.platform] // per_step)))

    def play(keys):
        _, states = jax.vmap(env.reset, in_axes=(0, None))(keys, params)

        def body(states, t):
            step_keys = jax.vmap(jax.random.fold_in, in_axes=(0, None))(keys, t)
            act_keys, env_keys = jnp.moveaxis(jax.vmap(jax.random.split)(step_keys), 1, 0)
            actions = jax.vmap(lambda k: jax.random.randint(k, (), 0, env.num_actions))(act_keys)
            obs, states, reward, terminated, truncated, _ = jax.vmap(env.step, in_axes=(0, 0, 0, None))(
                env_keys, states, actions, params)
            return states, (reward, terminated | truncated, obs[0, -1])
        return jax.lax.scan(body, states, jnp.arange(steps))[1]

    keys = jax.random.split(jax.random.key(0), NUM_ENVS)
    started = time.perf_counter()
    compiled = jax.jit(play).lower(keys).compile()
    compile_s = time.perf_counter() - started
    started = time.perf_counter()
    rewards, ended, frames = jax.block_until_ready(compiled(keys))
    seconds = time.perf_counter() - started
    rewards, ended, frames = np.asarray(rewards), np.asarray(ended), np.asarray(frames)

    returns, lengths = [], []
    for env_index in range(NUM_ENVS):
        total, length = 0.0, 0
        for t in range(steps):
            total += float(rewards[t, env_index])
            length += 1
            if ended[t, env_index]:
                returns.append(total)
                lengths.append(length)
                total, length = 0.0, 0
    # The preview: env 0's longest episode in the run (its last step, the game-over screen, left out).
    bounds = [0] + [t + 1 for t in np.flatnonzero(ended[:, 0])] + [steps]
    start, stop = max(zip(bounds[:-1], bounds[1:]), key=lambda b: b[1] - b[0])
    picks = np.linspace(start, max(start, stop - 2), PREVIEW_FRAMES).astype(int)
    palette = render.resolve_palette(spec.palette or render.DEFAULT_PALETTE)
    scale = 4 if spec.platform == "chip8" else 2
    strip = render.tile([render.to_rgb(frames[t], scale, palette) for t in picks], columns=PREVIEW_FRAMES, gap=4)
    return {
        "steps": steps, "num_envs": NUM_ENVS, "seconds": round(seconds, 2), "compile_seconds": round(compile_s, 1),
        "steps_per_second": round(NUM_ENVS * steps / seconds),
        "episodes": len(returns),
        "mean_return": round(float(np.mean(returns)), 2) if returns else None,
        "mean_length": round(float(np.mean(lengths)), 1) if lengths else None,
        "reward_per_1000_steps": round(1000 * float(rewards.sum()) / (steps * NUM_ENVS), 2),
        "preview": strip,
    }


def _row(game_id: str, m: dict) -> str:
    import octax_core

    spec = octax_core.get_spec(game_id)
    name = program_name(spec)
    source = SOURCE_URL.format(commit=ARCHIVE_COMMIT, name=name)
    title = programs()[name]["title"].replace("|", "/")
    if m["episodes"]:
        returns, lengths = f"{m['mean_return']:g} ({m['episodes']} episodes)", f"{m['mean_length']:g}"
    else:
        returns = f"none ended in {m['steps']} steps ({m['reward_per_1000_steps']:g} per 1000 steps)"
        lengths = f"> {m['steps']}"
    return (f"| **{game_id}** [{title}]({source}) | ![{game_id}](gallery/{game_id}.png) | "
            f"{spec.platform}, {spec.instructions_per_frame} ipf | {_keys(spec)} | {_authors(name)} | "
            f"{reward_sentence(game_id)} | {returns} | {lengths} | {m['steps_per_second']:,} |")


def write_page(measurements: dict) -> str:
    import octax_core

    _, games = _archive()
    slow = sorted((g for g in games if octax_core.get_spec(g).instructions_per_frame >= SLOW_TICKRATE),
                  key=lambda g: measurements[g]["steps_per_second"])
    lines = [
        "# The archive suite: a gallery",
        "",
        f"{len(games)} games of the [Chip8 Community Archive](https://github.com/JohnEarnest/chip8Archive) "
        f"(commit {ARCHIVE_COMMIT}), every one CC0 and shipped inside the package: installing it ([install.md](install.md)) "
        "and `gymnasium.make(\"octax/<id>-v0\")` need no ROM download. "
        "`octax_core.list_games(suite=\"archive\")` lists them; each game's module in "
        "`octax_core/env/games/archive/` documents its keys, start-up, score, lives and end, read from the "
        "program's Octo source. Each plays at its own platform, quirks, tickrate (ipf: instructions per "
        "60 Hz frame) and colours, from the archive's programs.json.",
        "",
        f"Measured by `python docs/gallery.py` on the development machine (2 CPU cores, no GPU): uniform "
        f"random actions in {NUM_ENVS} envs side by side (autoreset), for a fixed budget of emulated "
        "instructions per game, so fast games play up to 3,000 steps and the slowest a few dozen. Random "
        "return and episode length are the means over the episodes that ended (terminated or cut at the "
        "game's max steps) within those steps; steps/s is env steps per second over all 64 envs, "
        "compile time excluded. Previews: four frames spread over env 0's longest episode, in the game's palette.",
        "",
        HEADER,
    ]
    lines += [_row(game_id, measurements[game_id]) for game_id in games]
    lines += [
        "",
        "## Slow games",
        "",
        f"These run {SLOW_TICKRATE} or more instructions per frame (their programs.json tickrate), so "
        "each env step emulates thousands of instructions, many of them idle loops waiting for the next "
        "frame; SUPER-CHIP and XO-CHIP instructions also cost about 10 CHIP-8 ones here (every "
        "instruction pays for the 128x64 screen's scroll and sprite paths under `vmap`). Slowest first:",
        "",
        "| game | platform | ipf | steps/s (N=64) |",
        "|---|---|---|---|",
    ]
    for game_id in slow:
        spec = octax_core.get_spec(game_id)
        lines.append(f"| {game_id} | {spec.platform} | {spec.instructions_per_frame} | "
                     f"{measurements[game_id]['steps_per_second']:,} |")
    lines += ["", "## Left out", "",
              "Programs of the archive that are not here, and why:", ""]
    titles = programs()
    lines += [f"- {', '.join(titles[name]['title'] for name in names)}: {why}" for names, why in LEFT_OUT]
    lines.append("")
    return "\n".join(lines)


# The README's picture: the third preview frame of each, 4 x 2, on the games' own palettes.
STRIP_GAMES = ("Br8kout", "SuperOctogon", "Rockto", "FlutterBy", "Sw8Copter", "Carbon8", "Masquer8", "Snek")


def write_strip(folder: Path = None, games=STRIP_GAMES, gap: int = 4) -> Path:
    """gallery/strip.png from the saved previews (each is 4 frames of 256 x 128 with `gap` between)."""
    import cv2
    import numpy as np

    folder = FOLDER if folder is None else folder
    tiles = [cv2.imread(str(folder / f"{game}.png"))[:, 2 * (256 + gap):3 * 256 + 2 * gap] for game in games]
    grey = lambda h, w: np.full((h, w, 3), 40, np.uint8)
    rows = []
    for r in range(2):
        row = tiles[4 * r:4 * r + 4]
        rows.append(np.concatenate(sum(([t, grey(128, gap)] for t in row), [])[:-1], axis=1))
    strip = np.concatenate([rows[0], grey(gap, rows[0].shape[1]), rows[1]], axis=0)
    cv2.imwrite(str(folder / "strip.png"), strip)
    return folder / "strip.png"


def main(argv=None) -> int:
    import cv2

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="*", default=None, help="measure these games again")
    parser.add_argument("--page-only", action="store_true", help="rewrite the page from the saved measurements")
    args = parser.parse_args(argv)
    _, games = _archive()
    FOLDER.mkdir(exist_ok=True)
    saved = json.loads(MEASUREMENTS.read_text()) if MEASUREMENTS.exists() else {}
    todo = [] if args.page_only else (args.only if args.only is not None else [g for g in games if g not in saved])
    for game_id in todo:
        m = measure(game_id)
        cv2.imwrite(str(FOLDER / f"{game_id}.png"), cv2.cvtColor(m.pop("preview"), cv2.COLOR_RGB2BGR))
        saved[game_id] = m
        print(game_id, json.dumps(m), flush=True)
        MEASUREMENTS.write_text(json.dumps(dict(sorted(saved.items())), indent=1) + "\n")
    missing = [g for g in games if g not in saved]
    if missing:
        print(f"not measured yet: {missing}", file=sys.stderr)
        return 1
    PAGE.write_text(write_page(saved))
    print(f"wrote {PAGE} ({len(games)} games) and {write_strip()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
