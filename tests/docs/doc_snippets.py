"""Find the Python snippets of a Markdown page and run them as one reader would.

A reader pastes a page's ```python blocks, in order, into one Python session started in a clone
of the repository. `run_page` does the same: one fresh interpreter (so no import, cache or
registration of another page leaks in) in a scratch folder where `roms/`, `examples/` and `docs/`
are the repository's (symlinks), with one namespace shared by the page's blocks. A failure names
the page, the block and the Markdown line, with the block's text, because "a snippet failed" is
useless to whoever edits the page.

Two comments on a block's first line change how it is used:
* `not run: <why>`: the block needs what the test suite has not got (a GPU, several processes,
  a network, minutes); it is skipped, and the reason is there for the reader too.
* `# file: <path>` (the whole line): the page asks the reader to save the block as that file,
  which later blocks import; it is written there, not run.

This file is also the subprocess's program. `python doc_snippets.py --serve` is a page server: it
imports what most pages import (jax, numpy, gymnasium, octax_core, octax_gym, torch: ~1-3 s of CPU
per interpreter) once, without starting any JAX backend, then forks one child per page. Each child
is a fresh reader's session as far as a page can tell: its own process, cwd, environment, stdout
and stderr, started from the same just-imported state (nothing a page does reaches the next one),
and ended by a normal interpreter exit. Only the import seconds are shared.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
import traceback
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import List, Optional

REPO = Path(__file__).resolve().parents[2]

# What a page may read as `roms/...`, `examples/...` or `docs/...`, as in a clone; and the pages
# themselves, which tracebacks quote a failing line from.
LINKED = ("roms", "examples", "docs", "README.md")

_FENCE = re.compile(r"^(?P<indent>[ \t]*)(?P<fence>`{3,}|~{3,})[ \t]*(?P<info>[^`\s]*)")
_FILE = re.compile(r"^#\s*file:\s*(?P<path>\S+)\s*$")
_NOT_RUN = "not run:"


@dataclass(frozen=True)
class Block:
    """One fenced ```python block: where it is and what it holds."""

    page: str    # the page's path relative to the repository, e.g. "docs/env.md"
    number: int  # 1 for the page's first Python block
    line: int    # the Markdown line of the block's first code line (1-based)
    text: str    # the code, with the fence's indentation removed

    @property
    def first_line(self) -> str:
        return self.text.split("\n", 1)[0]

    @property
    def skipped(self) -> bool:
        """The block says it cannot run here (see the module docstring)."""
        return _NOT_RUN in self.first_line

    @property
    def save_as(self) -> Optional[str]:
        """The path the page asks the reader to save this block as, or None for a block to run."""
        match = _FILE.match(self.first_line.strip())
        return match.group("path") if match else None


def python_blocks(page: Path) -> List[Block]:
    """The page's ```python (or ```py) blocks, in order. Other fences (sh, bash, console, plain
    output) are stepped over whole, so a ``` line inside them never opens a block."""
    lines = page.read_text(encoding="utf-8").split("\n")
    name = page.resolve().relative_to(REPO).as_posix() if page.resolve().is_relative_to(REPO) else page.name
    blocks: List[Block] = []
    i = 0
    while i < len(lines):
        opening = _FENCE.match(lines[i])
        if opening is None:
            i += 1
            continue
        fence, indent = opening.group("fence"), opening.group("indent")
        closing = re.compile(rf"^[ \t]*{re.escape(fence[0])}{{{len(fence)},}}[ \t]*$")
        end = i + 1
        while end < len(lines) and not closing.match(lines[end]):
            end += 1
        if end == len(lines):
            raise ValueError(f"{name}: the code fence opened at line {i + 1} is never closed")
        if opening.group("info").lower() in ("python", "py"):
            body = [line[len(indent):] if line.startswith(indent) else line.lstrip() for line in lines[i + 1:end]]
            blocks.append(Block(page=name, number=len(blocks) + 1, line=i + 2, text="\n".join(body)))
        i = end + 1
    return blocks


def pages_with_python(repo: Path = REPO) -> List[Path]:
    """README.md and every docs/*.md that has at least one Python block: the pages to test."""
    pages = [repo / "README.md", *sorted((repo / "docs").glob("*.md"))]
    return [page for page in pages if page.is_file() and python_blocks(page)]


def scratch_clone(folder: Path, repo: Path = REPO) -> Path:
    """Make `folder` look like a clone to a snippet: `roms/`, `examples/`, `docs/`, README.md link to the repo's."""
    folder.mkdir(parents=True, exist_ok=True)
    for name in LINKED:
        (folder / name).symlink_to(repo / name, target_is_directory=(repo / name).is_dir())
    return folder


def snippet_env(scratch: Path) -> dict:
    """The subprocess's environment: ours, with the ROM folders made absolute (the scratch folder is
    another cwd), Minari's datasets kept in the scratch folder, and no display needed.

    torch gets one thread (as tests/gym_layer/test_sb3.py gives it): beside pytest's other worker
    on 2 cores, its second thread spins, and a conv of the paper's network cost 21 ms of CPU
    instead of 0.7 ms (docs/sb3.md's one PPO update: 21 s instead of about 2). Results are the
    same; only the page's cost changes."""
    env = dict(os.environ)
    rom_dirs = [str(Path(entry).expanduser().resolve()) for entry in env.get("OCTAX_ROM_DIR", "").split(os.pathsep) if entry]
    if rom_dirs:
        env["OCTAX_ROM_DIR"] = os.pathsep.join(rom_dirs)
    env["MINARI_DATASETS_PATH"] = str(scratch / "minari-datasets")
    env["MPLBACKEND"] = "Agg"
    env["OMP_NUM_THREADS"] = "1"
    env.pop("PYTHONPATH", None)  # a reader's session sees the installed packages, not the tests' paths
    return env


@dataclass(frozen=True)
class PageRun:
    returncode: int
    stdout: str
    stderr: str
    seconds: float      # wall clock
    cpu_seconds: float  # the page process's user + system time: what the page costs a loaded machine


# What the page server imports before it forks: the modules most pages import (torch for the sb3
# and torchrl pages). None of them starts a JAX backend or a thread (the server checks), so a
# fork is safe; a module a page needs beyond these it imports itself, as a reader would.
PRELOAD = ("numpy", "jax", "jax.numpy", "gymnasium", "octax_core", "octax_gym", "torch")


class PageServer:
    """The pytest side of `python doc_snippets.py --serve`: one server per test module, one forked
    child per page (see the module docstring). `close()` ends it."""

    def __init__(self, folder: Path):
        folder.mkdir(parents=True, exist_ok=True)
        self._log = folder / "server-stderr.txt"
        with open(self._log, "w") as log:
            self._process = subprocess.Popen(
                [sys.executable, str(Path(__file__).resolve()), "--serve"], cwd=folder,
                env=snippet_env(folder), stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=log, text=True)
        if self._read() != {"ready": True}:
            raise RuntimeError("the page server did not start")

    def _read(self) -> dict:
        line = self._process.stdout.readline()
        if not line:
            self._process.wait()
            raise RuntimeError(f"the page server ended (return code {self._process.returncode}):\n"
                               f"{self._log.read_text()[-6000:]}")
        return json.loads(line)

    def run(self, plan: Path, cwd: Path, env: dict, timeout: float) -> dict:
        self._process.stdin.write(json.dumps({"plan": str(plan), "cwd": str(cwd), "env": env, "timeout": timeout}) + "\n")
        self._process.stdin.flush()
        return self._read()

    def close(self) -> None:
        if self._process.poll() is None:
            self._process.stdin.close()
            try:
                self._process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self._process.kill()
                self._process.wait()


def run_page(page: Path, scratch: Path, server: PageServer, timeout: float = 300.0) -> PageRun:
    """Run `page`'s Python blocks in order in one fresh process of `server` whose cwd is `scratch`
    (already a `scratch_clone`). A non-zero return code means a block failed; stderr says which."""
    blocks = python_blocks(page)
    plan = scratch / ".snippet-blocks.json"
    plan.write_text(json.dumps([asdict(block) for block in blocks]), encoding="utf-8")
    start = time.perf_counter()
    reply = server.run(plan, scratch, snippet_env(scratch), timeout)
    seconds = time.perf_counter() - start
    stdout, stderr = (Path(reply[name]).read_text(encoding="utf-8", errors="replace") for name in ("stdout", "stderr"))
    if reply["timed_out"]:
        stderr += f"\n{page.name}: the page did not finish in {timeout:.0f} s and was killed\n"
    return PageRun(reply["returncode"], stdout, stderr, seconds, reply["cpu_seconds"])


def _numbered(text: str, first: int) -> str:
    return "\n".join(f"{first + k:5d} | {line}" for k, line in enumerate(text.split("\n")))


def _run_blocks(plan: Path) -> int:
    """The subprocess: run the blocks of `plan` in one namespace; on the first failure print which
    block and line failed, the traceback and the block, and return 1."""
    # As in `python` started in the clone: imports look in the cwd first, not in tests/docs.
    sys.path[0] = os.getcwd()
    namespace = {"__name__": "__main__", "__builtins__": __builtins__}
    for fields in json.loads(plan.read_text(encoding="utf-8")):
        block = Block(**fields)
        where = f"{block.page}: Python block {block.number} (line {block.line})"
        if block.skipped:
            print(f"{where}: skipped, {block.first_line.strip()}", file=sys.stderr)
            continue
        if block.save_as is not None:
            target = Path(block.save_as)
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_text(block.text + "\n", encoding="utf-8")
            continue
        # Blank lines in front, so that the traceback's line numbers are the Markdown page's.
        source = "\n" * (block.line - 1) + block.text + "\n"
        start = time.perf_counter()
        try:
            exec(compile(source, block.page, "exec"), namespace)
        except BaseException as error:  # noqa: BLE001 - any failure of a snippet, SystemExit included, is the report
            sys.stdout.flush()
            # The traceback from the snippet's own frame on: this driver's frame says nothing.
            trace = "".join(traceback.format_exception(type(error), error, error.__traceback__.tb_next))
            print(f"{where} failed:\n{trace}\nthe block:\n{_numbered(block.text, block.line)}", file=sys.stderr)
            return 1
        sys.stdout.flush()
        print(f"{where}: ran in {time.perf_counter() - start:.1f} s", file=sys.stderr)
    return 0


def _exit_as_python_would(code: int) -> None:
    """End a page's process as an interpreter ends, less the module teardown: the page's objects
    collected (their finalizers run), non-daemon threads joined, atexit handlers run, output
    flushed. Tearing down every module of the preload (torch, jax) would touch, and so copy, all of
    the server's memory: ~0.75 s of CPU a page for nothing a page can see."""
    import atexit
    import gc
    import threading

    gc.collect()
    threading._shutdown()  # noqa: SLF001 - what Py_FinalizeEx calls first
    atexit._run_exitfuncs()  # noqa: SLF001
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def _serve() -> int:
    """The page server: preload, then for each request line (a plan, a cwd, an environment and a
    timeout) fork a child that runs the plan as `python doc_snippets.py PLAN` would, and answer
    with its return code, CPU time and where its stdout and stderr are."""
    import importlib

    for name in PRELOAD:
        try:
            importlib.import_module(name)
        except ImportError:  # not installed here (torch without the torch extra): a page that needs it says so
            pass
    from jax._src import xla_bridge

    # A fork is only safe from a single-threaded process: JAX's backends start threads (and JAX
    # warns at a fork once they have), so the preload must not have started one.
    if xla_bridge.backends_are_initialized() or len(os.listdir("/proc/self/task")) != 1:
        print(f"the preload started a JAX backend or a thread; cannot fork pages safely", file=sys.stderr)
        return 3
    import gc

    gc.freeze()  # the preload's objects are never collected in a child, so never copied for it
    requests, replies = sys.stdin.buffer, sys.stdout
    print(json.dumps({"ready": True}), file=replies, flush=True)
    for line in requests:
        request = json.loads(line)
        plan = Path(request["plan"])
        out, err = plan.with_name(".snippet-stdout"), plan.with_name(".snippet-stderr")
        sys.stdout.flush()
        sys.stderr.flush()
        pid = os.fork()
        if pid == 0:  # the page's process
            null = os.open(os.devnull, os.O_RDONLY)
            os.dup2(null, 0)
            for fd, path in ((1, out), (2, err)):
                target = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
                os.dup2(target, fd)
                os.close(target)
            os.close(null)
            os.chdir(request["cwd"])
            os.environ.clear()
            os.environ.update(request["env"])
            sys.argv = [str(Path(__file__).resolve()), str(plan)]
            sys.stdin = open(os.devnull)
            if os.environ.get("OCTAX_COMPILE_LOG"):  # tests/compile_log.py: this page's compiles, by page
                sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
                from compile_log import record_compiles

                page = json.loads(plan.read_text(encoding="utf-8"))[0]["page"]
                os.environ["PYTEST_CURRENT_TEST"] = f"tests/docs/test_snippets.py::{page}"
                record_compiles(os.environ["OCTAX_COMPILE_LOG"])
            _exit_as_python_would(_run_blocks(plan))
        deadline, timed_out = time.monotonic() + request["timeout"], False
        while True:
            done, status, usage = os.wait4(pid, os.WNOHANG)
            if done:
                break
            if time.monotonic() > deadline:
                os.kill(pid, signal.SIGKILL)
                done, status, usage = os.wait4(pid, 0)
                timed_out = True
                break
            time.sleep(0.02)
        print(json.dumps({"returncode": os.waitstatus_to_exitcode(status), "timed_out": timed_out,
                          "cpu_seconds": usage.ru_utime + usage.ru_stime, "stdout": str(out), "stderr": str(err)}),
              file=replies, flush=True)
    os._exit(0)  # the tests are over; tearing the preload down would cost seconds for nothing


if __name__ == "__main__":
    sys.exit(_serve() if sys.argv[1:] == ["--serve"] else _run_blocks(Path(sys.argv[1])))
