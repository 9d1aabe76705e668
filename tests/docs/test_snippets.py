"""Every Python snippet of README.md and docs/*.md runs, so that none breaks unnoticed when pasted.

One test per page that has ```python blocks: the page's blocks run in order in one fresh
process (forked from a page server that imported jax, octax_gym and the rest once, so that no page
pays for those imports), from a scratch folder where `roms/`, `examples/` and `docs/` are the
repository's, as a reader would run them from a clone (tests/docs/doc_snippets.py). A block whose first line
says `not run:` is skipped; the page says why. The harness's own tests come first: a runner that
could not fail would make every page pass.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from doc_snippets import REPO, PageServer, pages_with_python, python_blocks, run_page, scratch_clone

PAGES = pages_with_python()


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    server = PageServer(tmp_path_factory.mktemp("page-server"))
    yield server
    server.close()


@pytest.fixture
def scratch(tmp_path) -> Path:
    return scratch_clone(tmp_path / "clone")


def _page(folder: Path, text: str) -> Path:
    page = folder / "page.md"
    page.write_text(textwrap.dedent(text), encoding="utf-8")
    return page


def test_blocks_are_the_python_fences_only(tmp_path):
    page = _page(tmp_path, """\
        # A page
        ```python
        x = 1
        ```
        ```bash
        echo not python
        ```
        ````
        ```python
        inside another fence: not a block
        ```
        ````
        - a list item:
          ```py
          y = x + 1
          ```
        """)
    blocks = python_blocks(page)
    assert [(b.number, b.line, b.text) for b in blocks] == [(1, 3, "x = 1"), (2, 15, "y = x + 1")]


def test_an_unclosed_fence_is_named(tmp_path):
    page = _page(tmp_path, "text\n```python\nx = 1\n")
    with pytest.raises(ValueError, match=r"page.md: the code fence opened at line 2 is never closed"):
        python_blocks(page)


def test_a_page_runs_in_order_in_one_namespace_from_the_clone(scratch, tmp_path, server):
    page = _page(tmp_path, """\
        ```python
        from pathlib import Path
        n = len(list(Path("roms").glob("*.8o")))
        ```
        ```python
        # not run: would fail if it ran
        raise RuntimeError("a skipped block ran")
        ```
        ```python
        # file: pkg/helper.py
        VALUE = 42
        ```
        ```python
        import sys; sys.path.insert(0, "pkg")
        from helper import VALUE
        assert n > 0 and VALUE == 42 and __name__ == "__main__"
        ```
        """)
    result = run_page(page, scratch, server)
    assert result.returncode == 0, result.stderr
    assert "Python block 2 (line 6): skipped, # not run: would fail if it ran" in result.stderr
    assert (scratch / "pkg" / "helper.py").read_text() == "# file: pkg/helper.py\nVALUE = 42\n"  # as the reader saves it


def test_a_failing_block_is_reported_with_its_line_and_text(scratch, tmp_path, server):
    page = _page(tmp_path, """\
        Intro.

        ```python
        import math
        ```

        ```python
        total = math.sqrt(4)
        print(total)
        print(key)
        ```
        ```python
        raise AssertionError("never reached: the page stops at its first failure")
        ```
        """)
    result = run_page(page, scratch, server)
    assert result.returncode == 1
    assert result.stdout == "2.0\n"
    assert "page.md: Python block 2 (line 8) failed:" in result.stderr
    assert "NameError: name 'key' is not defined" in result.stderr
    assert 'File "page.md", line 10' in result.stderr  # the Markdown page's line, not the block's
    assert "   10 | print(key)" in result.stderr
    assert "never reached" not in result.stderr


def test_pages_are_independent_processes_of_their_own(server, tmp_path):
    """What one page does (a JAX backend started, a module or the environment changed, the cwd)
    never reaches the next page: each is a new process forked from the untouched server."""
    first = _page(tmp_path, """\
        ```python
        import os, jax, octax_gym
        print(jax.numpy.zeros(2).sum(), os.environ["MINARI_DATASETS_PATH"])
        octax_gym.LEAKED = True
        os.environ["OCTAX_LEAKED"] = "1"
        ```
        """)
    (tmp_path / "2").mkdir()
    second = _page(tmp_path / "2", """\
        ```python
        import os, octax_gym, jax
        from pathlib import Path
        assert not hasattr(octax_gym, "LEAKED") and "OCTAX_LEAKED" not in os.environ
        assert Path.cwd().name == "b" and Path("roms").is_dir()
        print(int(jax.numpy.ones(3).sum()))
        ```
        """)
    runs = [run_page(page, scratch_clone(tmp_path / name), server) for page, name in ((first, "a"), (second, "b"))]
    assert [r.returncode for r in runs] == [0, 0], runs
    assert runs[0].stdout == f"0.0 {tmp_path / 'a' / 'minari-datasets'}\n" and runs[1].stdout == "3\n"
    assert all("fork" not in r.stderr for r in runs), runs  # JAX warns at a fork once a backend runs


def test_a_page_over_its_timeout_is_killed_and_named(server, scratch, tmp_path):
    page = _page(tmp_path, "```python\nimport time\ntime.sleep(60)\n```\n")
    result = run_page(page, scratch, server, timeout=1)
    assert result.returncode == -9 and result.seconds < 30
    assert "page.md: the page did not finish in 1 s and was killed" in result.stderr


def test_the_pages_are_the_readme_and_docs_with_python_blocks(tmp_path):
    (tmp_path / "docs").mkdir()
    _page(tmp_path, "```python\nx = 1\n```\n").rename(tmp_path / "README.md")
    _page(tmp_path, "```python\nx = 1\n```\n").rename(tmp_path / "docs" / "api.md")
    _page(tmp_path, "```sh\nls\n```\n").rename(tmp_path / "docs" / "cli.md")
    assert [p.relative_to(tmp_path).as_posix() for p in pages_with_python(tmp_path)] == ["README.md", "docs/api.md"]
    assert REPO / "README.md" in PAGES and REPO / "docs" / "env.md" in PAGES


@pytest.mark.parametrize("page", PAGES, ids=[page.relative_to(REPO).as_posix() for page in PAGES])
def test_page_snippets_run(page, scratch, server):
    result = run_page(page, scratch, server)
    assert result.returncode == 0, f"{page.relative_to(REPO)}'s snippets failed ({result.seconds:.0f} s):\n{result.stderr[-6000:]}"
