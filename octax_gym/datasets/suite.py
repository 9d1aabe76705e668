"""The dataset suite, in D4RL's shape: for each of its games, `octax/<Game>/random-v0`, `medium-v0`
and `expert-v0`, each collected from a named policy whose params travel with the dataset.

    octax-gym dataset suite --runs runs/suite            # every game; see docs/datasets.md
    octax-gym dataset suite --runs runs/suite --games Airplane Flak --steps 20000

The policies are PPO agents trained by the package's trainer with every evaluation's agents kept
(`octax-gym train ppo --games Airplane,Deep8,... --save-at-evals --out-dir runs/suite`: all the
games' agents in one program; the exact command is in docs/datasets.md and `make dataset-suite`
runs it). From a game's agent of that run (its first seed):

- expert: the final params (`agents/<Game>-seed<s>.msgpack`), scored by the run's last evaluation;
- medium: of the checkpoints part way through training (neither the untrained network nor the
  final one), the one whose evaluation return is nearest a third of the way from the random
  policy's return to the expert's (D4RL's "medium": a policy part way through training, about a
  third of the expert's performance over random);
- random: uniform actions.

Each dataset's metadata.json carries its policy card (`policy`: algorithm, steps trained, its
evaluation return and episodes, the random return, the params file and its SHA-256, the training
command), and the params themselves are copied next to its data (`<dataset>/policy/params.msgpack`),
so anyone can check, regenerate or extend it: `octax_gym.jax_policy.load_params` reads them.
Actions are sampled from the policy (the stochastic policy PPO is evaluated with), from a key
chain of the collection seed: the same runs and arguments give the same datasets.
"""

from __future__ import annotations

import csv
import dataclasses
import hashlib
import json
import re
import shutil
from pathlib import Path
from typing import Optional, Sequence

from octax_gym.envs.choices import UnknownOptionError

# Games where the package's PPO learns on two CPU cores (docs/results.md).
GAMES = ("Airplane", "Deep8", "Dodge", "Filter", "Flak", "Squash")
KINDS = ("random", "medium", "expert")
STEPS = 100_000  # per dataset
ENVS = 16  # lanes: 6,250 steps each, so episodes of up to the 2,000-step cap end inside a dataset, not only short ones
MEDIUM_FRACTION = 1 / 3  # of the way from random to expert
EVAL_MAX_STEPS = 2000  # the env's episode cap in the suite's datasets (and the runs' evaluations)


def dataset_id(game: str, kind: str) -> str:
    """`octax/<Game>/<kind>-v0`."""
    return f"octax/{game}/{kind}-v0"


@dataclasses.dataclass(frozen=True)
class PolicyCard:
    """A suite policy: where its params are and what they are worth."""

    kind: str  # medium or expert
    algorithm: str
    params_path: Path
    steps_trained: int
    eval_return: float
    eval_episodes: int
    random_return: float
    command: str

    def metadata(self) -> dict:
        return {"kind": self.kind, "algorithm": self.algorithm, "steps_trained": self.steps_trained,
                "eval_return": self.eval_return, "eval_episodes": self.eval_episodes,
                "random_return": self.random_return, "params_file": "policy/params.msgpack",
                "params_sha256": hashlib.sha256(self.params_path.read_bytes()).hexdigest(),
                "training_command": self.command}


def run_for(runs_dir, game: str) -> Path:
    """The training run that holds `game`'s agent: `runs_dir/<game>/` when there is one (a run per
    game), else `runs_dir` itself (one run of all the games, as `make dataset-suite` trains)."""
    runs_dir = Path(runs_dir)
    return runs_dir / game if (runs_dir / game).is_dir() else runs_dir


def pick_policies(run_dir, game: str) -> dict[str, PolicyCard]:
    """The medium and expert policies of `game` in one `octax-gym train ppo --save-at-evals` run
    (config.json, progress.csv, agents/<game>-seed<s>.msgpack and agents/<game>-seed<s>-step<N>.msgpack,
    s the run's first seed).

    Raises:
        FileNotFoundError: the run's files are missing (the message names the training command).
    """
    run_dir = Path(run_dir)
    hint = (f"train it with `octax-gym train ppo --games {game} --save-at-evals --out-dir {run_dir}` "
            "(docs/datasets.md; `make dataset-suite` trains every suite game)")
    missing = [str(p) for p in (run_dir / "config.json", run_dir / "progress.csv") if not p.is_file()]
    if missing:
        raise FileNotFoundError(f"no suite training run in {run_dir} (missing: {', '.join(missing)}); {hint}")
    config = json.loads((run_dir / "config.json").read_text())
    seed = int(config.get("seed", 0))
    name = f"{game}-seed{seed}"
    final = run_dir / "agents" / f"{name}.msgpack"
    checkpoints = {int(m.group(1)): p for p in (run_dir / "agents").glob(f"{name}-step*.msgpack")
                   if (m := re.fullmatch(re.escape(name) + r"-step(\d+)\.msgpack", p.name))}
    if game not in config.get("games", []) or not final.is_file() or not checkpoints:
        raise FileNotFoundError(f"{run_dir} holds no {name} agent kept at every evaluation (games: "
                                f"{', '.join(config.get('games', [])) or 'none'}; needs {final.name} and "
                                f"{name}-step<N>.msgpack files from --save-at-evals); {hint}")
    with open(run_dir / "progress.csv", newline="") as file:  # this agent's rows
        rows = [row for row in csv.DictReader(file) if row["game"] == game and int(row["seed"]) == seed]
    evals = {int(row["step"]): float(row["eval_mean_return"]) for row in rows}
    random_return = float(rows[0]["random_mean_return"])
    final_step = max(evals)
    expert_return = evals[final_step]
    command = " ".join(config.get("command", []))

    def card(kind, path, step):
        return PolicyCard(kind, config.get("algorithm", "ppo").upper(), path, step, evals[step],
                          int(config["eval_envs"]), random_return, command)

    target = random_return + MEDIUM_FRACTION * (expert_return - random_return)
    candidates = [step for step in checkpoints if step in evals and 0 < step < final_step]  # part way through
    if not candidates:
        raise FileNotFoundError(f"{run_dir}: no {name} agent between the start and the end of training with an "
                                "evaluation in progress.csv")
    medium = min(candidates, key=lambda step: (abs(evals[step] - target), step))
    return {"medium": card("medium", checkpoints[medium], medium), "expert": card("expert", final, final_step)}


def _num_actions(game: str) -> int:
    """The game's actions (no-op, then its keys): what a trainer's 17-wide agent is masked to."""
    from octax_core import get_spec

    return len(get_spec(game).action_keys) + 1


def build_suite(runs_dir, games: Sequence[str] = GAMES, kinds: Sequence[str] = KINDS, *, steps: int = STEPS,
                num_envs: int = ENVS, seed: int = 0, overwrite: bool = False, progress: bool = True) -> list:
    """Collects the suite's datasets (every game x kind asked for) from the training run in
    `runs_dir` (or a run per game, `runs_dir/<Game>/`: `run_for`); returns the `CollectResult`s, in order.

    Raises:
        UnknownOptionError: a game or kind outside the suite.
        FileNotFoundError: a game's training run is missing (for medium and expert).
        ValueError: a dataset exists and `overwrite` is False.
    """
    for name, given, valid in (("suite game", games, GAMES), ("dataset kind", kinds, KINDS)):
        for value in given:
            if value not in valid:
                raise UnknownOptionError(name, value, valid)
    from octax_gym import jax_policy
    from octax_gym.datasets.collect import collect_dataset

    results = []
    for game in games:
        cards = pick_policies(run_for(runs_dir, game), game) if set(kinds) - {"random"} else {}
        for kind in kinds:
            card: Optional[PolicyCard] = cards.get(kind)
            params = None if card is None else jax_policy.load_params(card.params_path)
            policy = "random" if card is None else jax_policy.sampling_policy(
                params, seed, num_actions=_num_actions(game))
            played = "epsilon-greedy" if card and jax_policy.describe(params).kind == "q_network" else "sampled"
            description = (f"octax/{game}-v0, {kind}: " + ("uniform random actions" if card is None else
                           f"{card.algorithm} after {card.steps_trained:,} steps (evaluation return "
                           f"{card.eval_return:.2f}; random {card.random_return:.2f}), actions {played}") +
                           f"; {steps} steps from {num_envs} lanes, episodes capped at {EVAL_MAX_STEPS} steps, "
                           f"seeds from {seed}. Built by `octax-gym dataset suite`.")
            result = collect_dataset(game, dataset_id(game, kind), steps, num_envs=num_envs, policy=policy, seed=seed,
                                     overwrite=overwrite, progress=progress, description=description,
                                     algorithm_name="random" if card is None else f"{card.algorithm}-{kind}",
                                     extra_metadata={"policy": None if card is None else card.metadata(),
                                                     "suite": {"game": game, "kind": kind}},
                                     max_episode_steps=EVAL_MAX_STEPS)
            if card is not None:
                (result.path / "policy").mkdir(exist_ok=True)
                shutil.copyfile(card.params_path, result.path / "policy" / "params.msgpack")
            results.append(result)
    return results
