"""The one tiny config every run of tests/train trains with (conftest.py says why one)."""

# 6 updates of 4 envs x 8 steps; evaluations every 2 updates (steps 0, 64, 128, 192) on 2 episodes of
# at most 30 steps; a resumable checkpoint every 2 updates (the last at update 4).
TINY = ("--num-envs", "4", "--num-steps", "8", "--num-minibatches", "2", "--update-epochs", "1",
        "--total-steps", "192", "--eval-every", "64", "--eval-envs", "2", "--eval-max-steps", "30",
        "--max-episode-steps", "20", "--checkpoint-every", "2", "--no-progress")
STEPS = (0, 64, 128, 192)  # the evaluations' steps of a TINY run

# The runs several modules read (conftest's `trained` makes each once a session): four agents in one
# program, and the lone run their (Deep8, seed 1) must equal, which test_resume also cuts and
# resumes and test_save_at_evals picks the suite's policies from.
TOGETHER = ("--games", "Airplane,Deep8", "--num-seeds", "2")
LONE = ("--games", "Deep8", "--seed", "1", "--save-at-evals")
