"""Every ``python`` and ``bash`` block of the README and of the site (docs/) runs, so that no
example can rot.

A page's python blocks run in order in one interpreter (a later block may use an earlier one's
names), then its bash blocks, one shell each, in a scratch folder holding links to the
repository's ``configs/`` and ``examples/`` (as the repository root would) with the venv's
``stsf-gym`` on ``PATH``. Blocks keep their own episodes short (``--seeds 1``, the fast sensor
mode, ``sim.max_episode_seconds``). A block that cannot run here says why in a
``<!-- not run: REASON -->`` line right above it; a block that shows an example file whole
(``<!-- example: examples/NAME.py -->`` right above it, fenced as ``{.python}`` so that ruff
leaves it alone) must equal the file, which tests/docs/test_examples.py runs: the code reads the
same on GitHub as on the site. Pages run two at a time.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import pytest
import yaml
from helpers import ROOT

PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
RUN = ("python", "bash")
NOT_RUN = re.compile(r"^<!-- not run: (.+) -->$")
EXAMPLE = re.compile(r"^<!-- example: (.+) -->$")
#: At most this many blocks may be marked not run, all pages together.
MOST_NOT_RUN = 6


@dataclass(frozen=True)
class Block:
    page: Path
    line: int
    language: str
    code: str
    not_run: str | None
    example: str | None = None  # the example file the block shows whole

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def blocks(page: Path) -> list[Block]:
    """The fenced blocks of ``page``, with the not-run reason written above each."""
    found, lines = [], page.read_text().splitlines()
    opened = None
    for number, line in enumerate(lines, 1):
        if opened is None and line.startswith("```"):
            opened = (number, line[3:].strip(), [])
        elif opened is not None and line.strip() == "```":
            start, language, code = opened
            above = lines[start - 2] if start > 1 else ""
            reason, example = NOT_RUN.match(above), EXAMPLE.match(above)
            found.append(
                Block(
                    page,
                    start,
                    language,
                    "\n".join(code) + "\n",
                    reason.group(1) if reason else None,
                    example.group(1) if example else None,
                )
            )
            opened = None
        elif opened is not None:
            opened[2].append(line)
    assert opened is None, f"{page}: a block opened at line {opened[0]} is never closed"
    return found


def runnable(page: Path) -> list[Block]:
    return [b for b in blocks(page) if b.language in RUN and b.not_run is None and not b.example]


def scratch(folder: Path) -> Path:
    for name in ("configs", "examples"):
        (folder / name).symlink_to(ROOT / name, target_is_directory=True)
    return folder


def run_page(page: Path, folder: Path) -> list[str]:
    """Run the page's blocks in ``folder``; the failures, each with its block's place."""
    env = {
        **os.environ,
        "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}",
        "MPLBACKEND": "Agg",
    }
    todo = runnable(page)
    python = [b for b in todo if b.language == "python"]
    commands = []
    if python:
        script = folder / "blocks.py"
        script.write_text("".join(f"# {b.where}\n{b.code}" for b in python))
        commands.append((python[0], [sys.executable, str(script)]))
    commands += [
        (b, ["bash", "-euo", "pipefail", "-c", b.code]) for b in todo if b.language == "bash"
    ]
    failures = []
    for block, command in commands:
        try:
            done = subprocess.run(
                command, cwd=folder, env=env, capture_output=True, text=True, timeout=300
            )
        except subprocess.TimeoutExpired:
            failures.append(f"{block.where} ({block.language}): over 300 s; shorten its episodes")
            continue
        if done.returncode != 0:
            output = f"{done.stdout[-2000:]}{done.stderr[-3000:]}"
            failures.append(f"{block.where} ({block.language}):\n{output}")
    return failures


@pytest.fixture(scope="module")
def results(tmp_path_factory) -> dict[Path, list[str]]:
    pages = [page for page in PAGES if runnable(page)]
    folders = [scratch(tmp_path_factory.mktemp(page.stem)) for page in pages]
    with ThreadPoolExecutor(max_workers=2) as pool:
        return dict(zip(pages, pool.map(run_page, pages, folders), strict=True))


@pytest.mark.slow
@pytest.mark.parametrize("page", [p for p in PAGES if runnable(p)], ids=lambda p: p.name)
def test_the_page_blocks_run(results, page):
    assert not results[page], "\n\n".join(results[page])


def test_blocks_not_run_are_few_and_say_why():
    marked = [b for page in PAGES for b in blocks(page) if b.not_run is not None]
    assert len(marked) <= MOST_NOT_RUN, [b.where for b in marked]
    for block in marked:
        assert len(block.not_run) >= 30, f"{block.where}: say why it cannot run"


def test_shown_examples_equal_their_files_and_are_run_by_their_test():
    shown = [b for page in PAGES for b in blocks(page) if b.example]
    assert shown
    tests = (ROOT / "tests" / "docs" / "test_examples.py").read_text()
    for block in shown:
        path = block.example
        assert (ROOT / path).is_file() and path.startswith("examples/"), path
        assert block.code == (ROOT / path).read_text(), f"{block.where}: copy {path} again"
        assert Path(path).name in tests or "examples/" in path  # every example: its own test


def test_no_page_includes_code_it_does_not_show():
    """An include (``--8<--``) shows nothing on GitHub: the code is written out instead."""
    for page in PAGES:
        assert "--8<--" not in page.read_text(), page


def test_yaml_blocks_parse():
    for page in PAGES:
        for block in blocks(page):
            if block.language == "yaml":
                assert yaml.safe_load(block.code) is not None, block.where


def test_the_readme_is_a_landing_page():
    readme = (ROOT / "README.md").read_text().splitlines()
    assert len(readme) <= 150
    top = "\n".join(readme[:15])
    assert "make demo" in top and "make test" in top
    animation = re.search(r"!\[[^\]]*\]\((docs/figures/[^)]+\.(?:gif|webp))\)", top)
    assert animation, "the README opens with the episode's animation"
    assert (ROOT / animation.group(1)).stat().st_size < 2_000_000
