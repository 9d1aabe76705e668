"""Which test files pytest-xdist hands to one worker together (tests/conftest.py's scheduler).

`--dist loadfile` hands out whole files. The files whose tests read the training runs of
tests/train/conftest.py's session fixture `trained` go as one unit, so that one worker trains each
run once a session: handed out file by file, they landed on both workers whenever the order put
them apart (as the order after a first run, from its compile-heavy seconds, did), and both trained
the same runs. tests/train/test_shared_runs.py fails when a file that asks for `trained` is
missing here.
"""

SHARED_RUN_FILES = ("tests/train/test_eval_games.py", "tests/train/test_many_agents.py",
                    "tests/train/test_multitask.py", "tests/train/test_resume.py",
                    "tests/train/test_save_at_evals.py")
SHARED_RUN_UNIT = "tests/train (the runs of `trained`)"


def work_unit(file: str) -> str:
    """The unit of work `file` (a path from the repository root) goes to a worker in."""
    return SHARED_RUN_UNIT if file in SHARED_RUN_FILES else file
