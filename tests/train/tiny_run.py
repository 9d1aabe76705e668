"""The one tiny config every run of tests/train trains with (conftest.py says why one)."""

# 6 updates of 4 envs x 8 steps; evaluations every 2 updates (steps 0, 64, 128, 192) on 2 episodes of
# at most 30 steps; a resumable checkpoint every 2 updates (the last at update 4).
TINY = ("--num-envs", "4", "--num-steps", "8", "--num-minibatches", "2", "--update-epochs", "1",
        "--total-steps", "192", "--eval-every", "64", "--eval-envs", "2", "--eval-max-steps", "30",
        "--max-episode-steps", "20", "--checkpoint-every", "2", "--no-progress")
STEPS = (0, 64, 128, 192)  # the evaluations' steps of a TINY run

# The runs several modules read (conftest's `trained` makes each once a session), all of one
# algorithm, as what they check (rows, agent files, the agent map's exactness, resuming, the kept
# agents) is the loop's and not an algorithm's: four agents in one program, and the lone run their
# (Deep8, seed 1) must equal, which test_resume also cuts and resumes and test_save_at_evals picks
# the suite's policies from. PQN, because PPO's update is trained end to end by the multitask
# (test_multitask, test_eval_games) and self-play (test_selfplay) runs, which are PPO's.
ALGORITHM = "pqn"
TOGETHER = ("--games", "Airplane,Deep8", "--num-seeds", "2")
LONE = ("--games", "Deep8", "--seed", "1", "--save-at-evals")


def multitask_flags(archive) -> tuple[str, ...]:
    """The multi-task run test_multitask and test_eval_games both read: one agent per seed trained on
    the dodger archive's train variants (lane i plays variant i mod 3, so 6 envs) and evaluated on
    its held-out test variants too (eval_games; so without the game's one-hot, which a held-out
    game has none of: test_multitask checks the one-hot on the trainer itself)."""
    return ("--games", f"archive:{archive}:train", "--eval-games", f"archive:{archive}:test", "--no-game-input",
            "--num-seeds", "2", "--num-envs", "6")
