"""Figures that cannot go stale unseen: every measured block of README.md and docs/ is tied to
the results it quotes (command and code digest shown) or listed with the reason it is not; the
stale and untied ones are listed (a warning) on every run, and the README quotes none
(``benchmarks/measured_blocks.py``)."""

from __future__ import annotations

import importlib.util
import json
import sys
import warnings
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SPEC = importlib.util.spec_from_file_location(
    "measured_blocks", ROOT / "benchmarks" / "measured_blocks.py"
)
measured = sys.modules["measured_blocks"] = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(measured)

PROVENANCE = {
    "command": "stsf-gym demo --seeds 1",
    "stsf_gym": {"source_digest": "0123abcd", "commit": None},
}


def test_every_block_is_tied_or_listed_and_the_readme_quotes_none_stale():
    blocks, problems = measured.check()
    assert blocks, "no measured block found"
    assert not problems, "\n".join(problems)
    unsettled = [block for block in blocks if block.state != "current"]
    if unsettled:
        warnings.warn("measured blocks not current:\n" + measured.listing(unsettled), stacklevel=1)


def _repository(tmp_path: Path, readme: str, not_tied: str = "") -> Path:
    (tmp_path / "docs").mkdir()
    (tmp_path / "benchmarks").mkdir()
    (tmp_path / "README.md").write_text(readme)
    (tmp_path / "benchmarks" / "measured_not_tied.yaml").write_text(not_tied)
    (tmp_path / "run.json").write_text(json.dumps({"provenance": PROVENANCE}))
    return tmp_path


def _block(name: str, body: str, results: str = "") -> str:
    tie = f" results: {results}" if results else ""
    return f"<!-- measured: {name} (begin){tie} -->\n{body}\n<!-- measured: {name} (end) -->\n"


SHOWN = "`stsf-gym demo --seeds 1` at `0123abcd`"


@pytest.mark.parametrize(
    ("readme", "not_tied", "digest", "problem"),
    [
        (_block("a", SHOWN, "run.json"), "", "0123abcd", None),
        (_block("a", SHOWN, "run.json"), "", "ffff0000", "README.md quotes 'a', which is stale"),
        (_block("a", "0.5 m", "run.json"), "", "0123abcd", "does not show run.json's"),
        (_block("a", SHOWN, "gone.json"), "", "0123abcd", "gone.json does not exist"),
        (_block("a", "0.5 m"), "", "0123abcd", "'a' names no results and"),
        (
            _block("a", "0.5 m"),
            "a: not kept",
            "0123abcd",
            "README.md quotes 'a', which is not tied",
        ),
        (_block("a", SHOWN, "run.json"), "b: gone", "0123abcd", "lists 'b', which is no block"),
        ("<!-- measured: a (begin) -->\n0.5 m\n", "a: x", "0123abcd", "'a' never ends"),
    ],
)
def test_the_rules_on_a_small_repository(tmp_path, readme, not_tied, digest, problem):
    root = _repository(tmp_path, readme, not_tied)
    blocks, problems = measured.check(root, digest)
    if problem is None:
        assert not problems and [b.state for b in blocks] == ["current"]
    else:
        assert any(problem in p for p in problems), problems


def test_an_untied_page_block_is_listed_with_its_reason(tmp_path):
    root = _repository(tmp_path, "# no figures\n", "a: its results were not kept")
    (root / "docs" / "page.md").write_text(_block("a", "0.5 m"))
    blocks, problems = measured.check(root, "0123abcd")
    assert not problems
    assert "its results were not kept" in measured.listing(blocks)
