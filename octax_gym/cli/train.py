"""`octax-gym train ALGO`: the package's trainer (`octax_gym.train`) from the shell (docs/training.md).

    octax-gym train ppo --games Airplane,Deep8 --num-seeds 2 --out-dir runs/ppo   # 4 agents, one program
    octax-gym train pqn --game Brix --seed 3 --total-steps 1000000
    octax-gym train ppo --preset paper --games octax16 --num-seeds 3              # the paper's table, on a GPU
    octax-gym train ppo --resume runs/ppo                                           # a run cut short, continued
    octax-gym train ppo --devices all --coordinator node0:29500 --num-processes 2 --process-id $RANK
    octax-gym train multitask --games Airplane,Brix,Deep8,Filter --num-envs 64       # one agent for all four
    octax-gym train multitask --games archive:gen/dodger:train --eval-games archive:gen/dodger:test --no-game-input
    octax-gym train selfplay --game Cycles --pool 4                                  # both seats, past selves
    octax-gym train bc --dataset octax/Flak/expert-v0 --num-seeds 2                  # offline, on a dataset

Settings start from a preset (`--preset cpu`, the default, or `paper`) and each flag given
overrides one. A setting no run can use, or one of another algorithm, is refused with its name.
flax and optax (the train extra) are imported only when the command runs.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

TRAIN_HINT = "pip install 'octax-gym[train]'"
ALGORITHMS = ("ppo", "pqn", "multitask", "selfplay", "bc", "cql")
PPO_ONLY = ("gae_lambda", "clip_eps", "clip_value_loss", "vf_coef", "ent_coef", "ent_coef_final")
EXPLORATION = ("q_lambda", "epsilon_start", "epsilon_finish", "epsilon_fraction")
PQN_ONLY = EXPLORATION + ("eval_epsilon",)  # eval_epsilon: CQL's too
MULTITASK_ONLY = ("game_input",)
OFFLINE_ONLY = ("dataset",)
CQL_ONLY = ("cql_alpha", "target_every")
SELFPLAY_ONLY = ("pool", "pool_prob", "eval_opponents")
NOT_OF = {"ppo": PQN_ONLY + MULTITASK_ONLY + OFFLINE_ONLY + CQL_ONLY + SELFPLAY_ONLY,
          "pqn": PPO_ONLY + MULTITASK_ONLY + OFFLINE_ONLY + CQL_ONLY + SELFPLAY_ONLY,
          "multitask": PQN_ONLY + OFFLINE_ONLY + CQL_ONLY + SELFPLAY_ONLY,
          "selfplay": PQN_ONLY + MULTITASK_ONLY + OFFLINE_ONLY + CQL_ONLY,
          "bc": PPO_ONLY + PQN_ONLY + MULTITASK_ONLY + CQL_ONLY + SELFPLAY_ONLY,
          "cql": PPO_ONLY + EXPLORATION + MULTITASK_ONLY + SELFPLAY_ONLY}
ENV_FLAGS = {"max_episode_steps": int, "frames_per_step": int, "repeat_action_probability": float, "noop_max": int}
SETTINGS = {  # flag -> (type, help); each a TrainConfig field
    "seed": (int, "the first seed: seeds S..S+N-1 each train one agent per game"),
    "num_seeds": (int, "seeds per game (agents: games x seeds, one program)"),
    "total_steps": (int, "env steps per agent (rounded down to whole updates)"),
    "num_envs": (int, "training envs per agent"),
    "num_steps": (int, "rollout length per env and update"),
    "update_epochs": (int, "passes over each rollout"),
    "num_minibatches": (int, "minibatches per epoch (num_envs * num_steps must divide)"),
    "learning_rate": (float, "Adam step size"),
    "gamma": (float, "discount"),
    "max_grad_norm": (float, "global gradient-norm clip"),
    "eval_every": (int, "env steps per agent between evaluations (and at both ends); 0: both ends only"),
    "eval_envs": (int, "evaluation episodes per agent and policy (greedy and sampled)"),
    "eval_max_steps": (int, "step cap of an evaluation (default: the game's episode cap)"),
    "eval_noop_max": (int, "evaluation episodes start after 0..N no-ops (default 30: distinct episodes)"),
    "checkpoint_every": (int, "updates between resumable checkpoints in OUT/resume (0: none)"),
    "gae_lambda": (float, "PPO: GAE lambda"),
    "clip_eps": (float, "PPO: ratio (and value) clip"),
    "vf_coef": (float, "PPO: value loss weight"),
    "ent_coef": (float, "PPO: entropy bonus weight"),
    "ent_coef_final": (float, "PPO: the entropy weight decays linearly from --ent-coef to this over the run "
                              "(default: constant)"),
    "q_lambda": (float, "PQN: lambda of the Q(lambda) returns"),
    "epsilon_start": (float, "PQN: exploration rate of the first rollout"),
    "epsilon_finish": (float, "PQN: exploration rate after the decay"),
    "epsilon_fraction": (float, "PQN: fraction of the steps over which epsilon decays"),
    "eval_epsilon": (float, "PQN, CQL: exploration rate of the sampled evaluation"),
    "dataset": (str, "bc, cql: the Minari dataset id to train on (its game and env options are the run's)"),
    "cql_alpha": (float, "CQL: weight of the conservative regulariser"),
    "target_every": (int, "CQL: updates between copies of the target network"),
    "pool": (int, "selfplay: K past selves (a snapshot per evaluation) as opponents; 0: pure self-play"),
    "pool_prob": (float, "selfplay: per env and update, the chance that one seat is played by a past self"),
    "eval_opponents": (lambda text: tuple(name.strip() for name in text.split(",")),
                       "selfplay: the evaluation's opponents, comma-separated players (ladder rungs random, eps0.5, "
                       "eps0.25, eps0.1, scripted; noop; eps<p>); default random,eps0.5,scripted"),
}


def add_commands(commands: argparse._SubParsersAction) -> None:
    train = commands.add_parser(
        "train", help="train PPO or PQN agents in pure JAX: many games x seeds in one program (or multi-task, "
                      "self-play)",
        description="Trains one agent per game and seed (not one agent for all games) in one jitted program, "
                    "(multitask: one PPO agent per seed for all the games, lane i playing game i mod G; selfplay: "
                    "one PPO agent per seed on both seats of a two-player game, evaluated in matches against "
                    "random and scripted players; bc, cql: offline, from the Minari dataset --dataset), "
                    "writing OUT/progress.csv (a row per game, seed and evaluation), OUT/learning_curve.png, "
                    "OUT/agents/<game>-seed<s>.msgpack and OUT/summary.json. Needs the train extra: "
                    + TRAIN_HINT + ". See docs/training.md.")
    train.add_argument("algorithm", choices=ALGORITHMS, metavar="ALGO",
                       help="ppo, pqn, multitask, selfplay (a two-player game), or bc and cql (offline, on --dataset)")
    train.add_argument("--games", "--game", dest="games", metavar="G[,G...]",
                       help="game ids, comma-separated, octax16 (the paper's 16), or archive:DIR[:train|test] (an "
                            "octax-gym generate archive's accepted games); default Brix")
    train.add_argument("--eval-games", default=None, metavar="G[,G...]",
                       help="ppo (one game), pqn (one game), multitask: games every agent is evaluated on too but "
                            "never trains on, as --games (e.g. archive:DIR:test, the held-out variants); their "
                            "progress.csv rows have split 'eval'")
    train.add_argument("--preset", default="cpu", metavar="NAME",
                       help="starting settings: cpu (64 envs, 655,360 steps; the default) or paper (512 envs x 32 "
                            "steps, 4 x 32 minibatches, Adam 5e-4, 5M steps an agent)")
    for name, (kind, text) in SETTINGS.items():
        train.add_argument("--" + name.replace("_", "-"), type=kind, default=None, help=text)
    train.add_argument("--anneal-lr", action=argparse.BooleanOptionalAction, default=None,
                       help="decay the learning rate linearly to 0 (the paper: constant)")
    train.add_argument("--clip-value-loss", action=argparse.BooleanOptionalAction, default=None,
                       help="PPO: clip the value loss as CleanRL's Atari PPO does (default on)")
    train.add_argument("--save-at-evals", action="store_true", default=None,
                       help="keep each evaluation's agents too, as OUT/agents/<game>-seed<s>-step<N>.msgpack (the "
                            "policies part way through training that `octax-gym dataset suite` picks from)")
    train.add_argument("--game-input", action=argparse.BooleanOptionalAction, default=None,
                       help="multitask: the game's one-hot joins the network's features (default on; off: the "
                            "screen alone tells the games apart)")
    for name, kind in ENV_FLAGS.items():
        train.add_argument("--" + name.replace("_", "-"), type=kind, default=None,
                           help="an env option for every game (octax_core.make); default: the game's")
    train.add_argument("--mirror", action="store_true", default=None,
                       help="selfplay, a game whose sides mirror each other (Cycles): seat 1 sees and plays the "
                            "mirror image (make_multi(mirror=True)), so the network plays both seats from one side")
    train.add_argument("--devices", default=None, metavar="all",
                       help="all: every agent's envs split over every device (data-parallel); default one device")
    train.add_argument("--coordinator", default=None, metavar="HOST:PORT",
                       help="with --devices all over several processes: process 0's address "
                            "(octax_gym.distributed.initialize; without it, SLURM or torchrun-style variables)")
    train.add_argument("--num-processes", type=int, default=None, help="processes in a multi-process run")
    train.add_argument("--process-id", type=int, default=None, help="this process's rank in a multi-process run")
    train.add_argument("--agent-map", default=None, choices=("auto", "vmap", "map"),
                       help="how agents share the program: vmap (batched, for a GPU), map (one after another: "
                            "bit for bit a lone run's), auto (map on a CPU, vmap elsewhere; the default)")
    train.add_argument("--network-layout", default=None, choices=("image", "paper"),
                       help="how the conv torso reads the frames: image (the paper's text: the 64 x 32 screen, "
                            "frames as channels; the default) or paper (the paper's code: frames x rows, the 64 "
                            "columns as channels), which learns Brix where image does not (docs/results/brix.md)")
    train.add_argument("--out-dir", type=Path, default=None, metavar="OUT",
                       help="where the run writes (default runs/<algo>-<games>-s<seed>)")
    train.add_argument("--resume", type=Path, default=None, metavar="OUT",
                       help="continue the run in OUT (made with --checkpoint-every) from its last checkpoint, "
                            "with OUT/config.json; no other setting may be given")
    train.add_argument("--no-progress", action="store_true", help="no progress bar")
    train.set_defaults(func=_cmd_train)


def config_from_args(args: argparse.Namespace):
    """The checked `TrainConfig` the flags ask for (the preset, then each flag given).

    Raises:
        ValueError: a bad value, or a setting of the other algorithm (named).
        ImportError: the train extra is missing.
    """
    _import_train()
    from octax_gym.train import preset, resolve_games

    switches = ("anneal_lr", "clip_value_loss", "game_input", "save_at_evals")
    given = {name: getattr(args, name) for name in (*SETTINGS, *switches) if getattr(args, name) is not None}
    if wrong := [name for name in given if name in NOT_OF[args.algorithm]]:
        flags = ", ".join("--" + n.replace("_", "-") for n in wrong)
        owners = sorted({a for a, names in NOT_OF.items() if not set(wrong) & set(names)} - {args.algorithm})
        raise ValueError(f"{flags}: not a setting of {args.algorithm} (of {' and '.join(owners)})")
    if args.games is not None:
        given["games"] = resolve_games(args.games)
    if args.eval_games is not None:
        given["eval_games"] = resolve_games(args.eval_games)
    if args.algorithm in ("bc", "cql") and given.get("dataset"):  # the dataset's game and env options
        from octax_gym.train.offline import dataset_env

        game, dataset_overrides = dataset_env(given["dataset"])
        if given.get("games", (game,)) != (game,):
            raise ValueError(f"--games: {given['dataset']} is a dataset of {game}, not of {', '.join(given['games'])}")
        given["games"], given["env_overrides"] = (game,), dataset_overrides
    for name in ("devices", "agent_map", "network_layout"):
        if getattr(args, name) is not None:
            given[name] = getattr(args, name)
    overrides = tuple((name, getattr(args, name)) for name in ENV_FLAGS if getattr(args, name) is not None)
    if args.mirror:
        overrides += (("mirror", True),)
    if overrides and "dataset" in given:
        raise ValueError(f"--{overrides[0][0].replace('_', '-')}: an offline run plays the env its dataset was "
                         "collected in (its options are the dataset's)")
    if overrides:
        given["env_overrides"] = overrides
    return preset(args.preset, args.algorithm, **given)


def _cmd_train(args: argparse.Namespace) -> int:
    distributed = (args.coordinator, args.num_processes, args.process_id)
    if any(value is not None for value in distributed):  # before anything computes with JAX
        import octax_gym.step.distributed

        try:
            octax_gym.step.distributed.initialize(*distributed)
        except octax_gym.step.distributed.DistributedInitError as exc:  # a start-up mistake, named: no traceback
            raise ValueError(str(exc)) from None
    if args.resume is not None:
        config, out_dir = _resumed(args)
    else:
        config = config_from_args(args)
        out_dir = args.out_dir or Path("runs") / _run_name(config)
    from octax_gym.train import train

    print(f"{config.algorithm} on {', '.join(config.game_ids)} x seeds {config.seeds} -> {out_dir}")
    train(config, out_dir, progress=not args.no_progress, resume=args.resume is not None)
    print(f"wrote {out_dir / 'progress.csv'}, {out_dir / 'learning_curve.png'} and {out_dir / 'agents'}/")
    return 0


def _resumed(args: argparse.Namespace):
    """The config of the run in `--resume OUT` (its config.json); refuses other settings."""
    defaults = {"games": None, "eval_games": None, "preset": "cpu", "devices": None, "agent_map": None,
                "network_layout": None, "out_dir": None, "anneal_lr": None,
                "clip_value_loss": None, "game_input": None, "save_at_evals": None, "mirror": None,
                **{n: None for n in (*SETTINGS, *ENV_FLAGS)}}
    if given := [name for name, default in defaults.items() if getattr(args, name) != default]:
        raise ValueError(f"--resume takes the run's own settings (OUT/config.json); drop "
                         f"{', '.join('--' + n.replace('_', '-') for n in given)}")
    _import_train()
    import dataclasses

    from octax_gym.train import TrainConfig

    path = args.resume / "config.json"
    if not path.is_file():
        raise FileNotFoundError(f"--resume: no config.json in {args.resume} (not the folder of an octax-gym train run)")
    saved = json.loads(path.read_text())
    fields = {field.name for field in dataclasses.fields(TrainConfig)}
    values = {k: v for k, v in saved.items() if k in fields}
    values["games"] = tuple(values["games"])
    values["eval_games"] = tuple(values.get("eval_games", ()))
    values["env_overrides"] = tuple(tuple(pair) for pair in values.get("env_overrides", ()))
    if "eval_opponents" in values:
        values["eval_opponents"] = tuple(values["eval_opponents"])
    if values["algorithm"] != args.algorithm:
        raise ValueError(f"--resume: {args.resume} is a {values['algorithm']} run, not {args.algorithm}")
    return TrainConfig(**values).check(), args.resume


def _run_name(config) -> str:
    from octax_core.env.mix import MIXES

    games = next((name for name, mix in MIXES.items() if tuple(config.game_ids) == mix), "-".join(config.game_ids))
    return f"{config.algorithm}-{games}-s{config.seed}" + (f"-n{config.num_seeds}" if config.num_seeds > 1 else "")


def _import_train() -> None:
    try:
        import octax_gym.train  # noqa: F401
    except ImportError as exc:
        raise ImportError(f"octax-gym train needs the train extra: {TRAIN_HINT} ({exc})") from exc
