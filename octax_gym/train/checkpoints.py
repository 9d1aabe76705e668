"""What a run keeps on disk: each agent's params, and the resumable checkpoint of the whole run.

* `save_agents`: `OUT/agents/<game>-seed<s>.msgpack` (`multitask-seed<s>`), one file per agent (flax serialization of
  `{"params": ...}`, what `octax_gym.jax_policy` and `octax-gym play --agent` read), rewritten at
  every evaluation, so a run cut short keeps its last evaluated agents; with `save_at_evals`
  (`--save-at-evals`) each evaluation's agents are also kept as `<name>-step<N>.msgpack`, the
  policies part way through training that the dataset suite picks its medium ones from.
* `Checkpoints`: `OUT/resume/checkpoint.msgpack` (every agent's runner: params, optimizer and env
  states, keys as raw data; the loop's position: updates done, training seconds, the metric sums
  since the last evaluation) and `checkpoint.json` (the position, readable). Each is written to a
  temporary file and renamed over the last, so a kill at any moment leaves a whole checkpoint.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional, Sequence

import flax.serialization
import jax
import jax.numpy as jnp
import numpy as np


def save_agents(out_dir: Path, names: Sequence[str], params, write: bool = True,
                step: Optional[int] = None, view: Optional[dict] = None) -> list[Path]:
    """Each agent's slice of `params` (leading agent axis) to `OUT/agents/<name>.msgpack`, and
    with `step` to `<name>-step<step>.msgpack` too; every process takes part (`host_values`),
    process 0 writes. `view` (`jax_policy.VIEW_KEYS`: {"mirror": True} for a --mirror run) is saved
    beside the params when given, so whoever plays the agent sees its game as it did."""
    params = host_values(params)
    paths = [Path(out_dir) / "agents" / f"{name}.msgpack" for name in names]
    if write:
        paths[0].parent.mkdir(parents=True, exist_ok=True)
        for i, path in enumerate(paths):
            agent = jax.tree.map(lambda x: x[i], params)
            data = flax.serialization.to_bytes({**agent, "view": dict(view)} if view else agent)
            _replace(path, data)
            if step is not None:
                _replace(path.with_name(f"{names[i]}-step{step}.msgpack"), data)
    return paths


def host_values(tree):
    """Every leaf as a numpy array on every process: a multi-process array that is not fully
    replicated is gathered (`process_allgather`, a collective: every process must call this)."""
    from jax.experimental import multihost_utils

    def leaf(x):
        if isinstance(x, jax.Array) and not x.is_fully_addressable and not x.is_fully_replicated:
            return np.asarray(multihost_utils.process_allgather(x, tiled=True))
        return np.asarray(x)
    return jax.tree.map(leaf, tree)


class Checkpoints:
    """A run's resumable checkpoint in `folder` (see the module docstring)."""

    def __init__(self, folder: Path, write: bool = True):
        self.folder, self.write = Path(folder), write
        self.path, self.info_path = self.folder / "checkpoint.msgpack", self.folder / "checkpoint.json"

    def save(self, runner, position: dict) -> None:
        leaves = jax.tree.leaves(host_values(keys_as_data(runner)))  # every process takes part
        if not self.write:
            return
        self.folder.mkdir(parents=True, exist_ok=True)
        payload = {"runner": {str(i): np.asarray(leaf) for i, leaf in enumerate(leaves)},
                   "update": position["update"], "train_s": position["train_s"],
                   "totals": {k: np.asarray(v, np.float64) for k, v in position["totals"].items()}}
        _replace(self.path, flax.serialization.msgpack_serialize(payload))
        _replace(self.info_path, (json.dumps({"update": position["update"]}) + "\n").encode())

    def load(self, template):
        """The runner (shaped as `template`, a freshly initialised one) and the position.

        Raises:
            FileNotFoundError: no checkpoint (the message says how a run writes one).
            ValueError: a checkpoint of another shape (another config or algorithm).
        """
        if not self.path.is_file():
            raise FileNotFoundError(f"no checkpoint to resume from at {self.path} (was the run started with "
                                    "--checkpoint-every N, and had it written one?)")
        state = flax.serialization.msgpack_restore(self.path.read_bytes())
        expected, treedef = jax.tree.flatten(keys_as_data(template))
        leaves = [state["runner"][str(i)] for i in range(len(state["runner"]))]
        if [(np.shape(a), np.asarray(a).dtype) for a in leaves] != [(a.shape, a.dtype) for a in expected]:
            raise ValueError(f"{self.path} holds a runner of another shape (another config or algorithm)")
        runner = jax.tree.map(lambda t, x: jax.random.wrap_key_data(x, impl=jax.random.key_impl(t))
                              if is_key(t) else jnp.asarray(x), template, treedef.unflatten(leaves))
        totals = {k: (int(v) if k == "updates" else np.asarray(v, np.float64)) for k, v in state["totals"].items()}
        return runner, {"update": int(state["update"]), "train_s": float(state["train_s"]), "totals": totals}


def is_key(x) -> bool:
    return isinstance(x, jax.Array) and jnp.issubdtype(x.dtype, jax.dtypes.prng_key)


def keys_as_data(tree):
    """Typed PRNG keys as their raw uint32 data (what msgpack and device placement can carry)."""
    return jax.tree.map(lambda x: jax.random.key_data(x) if is_key(x) else x, tree)


def _replace(path: Path, data: bytes) -> None:
    temporary = path.with_suffix(path.suffix + ".tmp")
    temporary.write_bytes(data)
    temporary.replace(path)
