"""`octax-gym dataset finish` on a damaged dataset folder (octax_gym/datasets/damage.py): one error
line naming the damaged file and what to do, the folder left as it was.

At 68402af the same commands printed h5py's "Unable to synchronously open file (file signature
not found)" naming no file, a raw AttributeError traceback, Minari's bare AssertionError, or
"already one file; 9 episodes" for a main_data.hdf5 of random bytes. Two synthetic datasets are
written once (tests/dataset_kill_worker.py's episodes): one in parts, as a killed collection
leaves it, one finished into one file; each case damages a copy.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

minari = pytest.importorskip("minari")

from gymnasium import spaces  # noqa: E402

from octax_gym import cli  # noqa: E402
from octax_gym.datasets import DamagedDatasetError, finish_dataset, recovery_spec, storage  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import dataset_kill_worker as synthetic  # noqa: E402

DATA = Path(synthetic.DATASET_ID) / "data"


@pytest.fixture(scope="module")
def written(tmp_path_factory) -> dict[str, Path]:
    """{"parts": root of a dataset of two parts (no close), "one file": root of a closed one}."""
    roots = {}
    before = os.environ.get("MINARI_DATASETS_PATH")
    try:
        for form in ("parts", "one file"):
            root = roots[form] = tmp_path_factory.mktemp(form.replace(" ", "_"))
            os.environ["MINARI_DATASETS_PATH"] = str(root)
            writer = storage.DatasetWriter(synthetic.DATASET_ID, recovery_spec("octax/Brix-v0", {}),
                                           spaces.Box(0, 1, synthetic.SHAPE, np.uint8), spaces.Discrete(5),
                                           flush_steps=10**9, metadata={})
            for f in range(2):
                for e in range(f * synthetic.EPISODES_PER_FLUSH, (f + 1) * synthetic.EPISODES_PER_FLUSH):
                    writer.add(synthetic.episode(e), cut=False)
                writer.flush()
            if form == "one file":
                writer.close()
    finally:
        if before is None:
            os.environ.pop("MINARI_DATASETS_PATH", None)
        else:
            os.environ["MINARI_DATASETS_PATH"] = before
    return roots


def truncate(path: Path) -> None:
    path.write_bytes(path.read_bytes()[:700])


def random_bytes(path: Path) -> None:
    path.write_bytes(np.random.default_rng(0).integers(0, 256, 5000, np.uint8).tobytes())


def edit_metadata(change):
    def damage(path: Path) -> None:
        metadata = json.loads(path.read_text())
        change(metadata)
        path.write_text(json.dumps(metadata))
    return damage


# (form, damaged file under data/, damage, words the message must hold besides the file's name)
CASES = {
    "main truncated": ("parts", "main_data.hdf5", truncate, "not a readable HDF5 file"),
    "main random bytes": ("one file", "main_data.hdf5", random_bytes, "not a readable HDF5 file"),
    "main missing": ("one file", "main_data.hdf5", Path.unlink, "is missing"),
    "part truncated": ("parts", "parts/part-00001.hdf5", truncate, "not a readable HDF5 file"),
    "part missing": ("parts", "parts/part-00000.hdf5", Path.unlink, "is missing"),
    "metadata missing": ("parts", "metadata.json", Path.unlink, "is missing"),
    "metadata cut JSON": ("one file", "metadata.json", lambda p: p.write_text('{"total_episodes": 6, '),
                          "is not valid JSON"),
    "metadata a list": ("parts", "metadata.json", lambda p: p.write_text("[1, 2]"), "holds a JSON list"),
    "metadata no spaces": ("one file", "metadata.json", edit_metadata(lambda m: m.pop("observation_space")),
                           "has observation_space = null"),
    "metadata count a string": ("one file", "metadata.json",
                                edit_metadata(lambda m: m.update(total_episodes="6")), "has total_episodes = \"6\""),
    "metadata counts too many": ("one file", "metadata.json", edit_metadata(lambda m: m.update(total_episodes=7)),
                                 "data/main_data.hdf5 has no episode_6"),
}


def damaged_copy(written, tmp_path, case) -> tuple[Path, Path]:
    """(the damaged copy's dataset folder, the damaged file)."""
    form, file, damage, _ = CASES[case]
    shutil.copytree(written[form], tmp_path / "root")
    folder = tmp_path / "root" / synthetic.DATASET_ID
    damage(folder / "data" / file)
    return folder, folder / "data" / file


def snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.mark.parametrize("case", list(CASES))
def test_finish_names_the_damaged_file_and_changes_nothing(written, tmp_path, capsys, case):
    folder, damaged = damaged_copy(written, tmp_path, case)
    before = snapshot(folder)
    assert cli.main(["dataset", "finish", str(folder)]) == 1
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in captured.err, captured.err
    line = lines[0]
    assert line.startswith(f"octax-gym: error: dataset {folder} is damaged: "), line
    assert str(damaged.relative_to(folder)) in line and CASES[case][3] in line, line
    assert "Restore the file from a copy, or collect the dataset again" in line, line
    assert snapshot(folder) == before


def test_the_api_raises_a_value_error_naming_the_file(written, tmp_path):
    folder, damaged = damaged_copy(written, tmp_path, "metadata no spaces")
    with pytest.raises(DamagedDatasetError) as raised:
        finish_dataset(folder)
    assert isinstance(raised.value, ValueError) and raised.value.path == damaged


@pytest.mark.parametrize("form", ["parts", "one file"])
def test_whole_datasets_still_finish(written, tmp_path, capsys, form):
    shutil.copytree(written[form], tmp_path / "root")
    folder = tmp_path / "root" / synthetic.DATASET_ID
    assert cli.main(["dataset", "finish", str(folder)]) == 0
    state = "made one file" if form == "parts" else "already one file"
    assert capsys.readouterr().out.strip() == f"{folder}: {state}; 6 episodes, {sum(synthetic.E_STEPS[:6])} steps"
    assert not (folder / "data" / "parts").exists()
