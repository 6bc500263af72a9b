"""Figures that cannot go stale unseen: every measured block of README.md and docs/ is tied to
the results it quotes (command and code digest shown) or listed with the reason it is not; the
stale and untied ones are listed (a warning) on every run, and the README quotes none; a block
goes stale when code its results' run loaded changes, not any code
(``benchmarks/measured_blocks.py``)."""

from __future__ import annotations

import importlib.util
import json
import sys
import warnings
from pathlib import Path

import pytest
from helpers import ROOT

from stsf_gym.results.behaviour import VERSIONS, code_digest
from stsf_gym.results.code_identity import file_digest

SPEC = importlib.util.spec_from_file_location(
    "measured_blocks", ROOT / "benchmarks" / "measured_blocks.py"
)
measured = sys.modules["measured_blocks"] = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(measured)

PROVENANCE = {
    "command": "stsf-gym demo --seeds 1",
    "stsf_gym": {"source_digest": "0123abcd", "commit": None, "behaviour": {"world": 1}},
}


@pytest.fixture(autouse=True)
def world_v1(monkeypatch):
    """The small repositories' runs recorded the world's version 1: make it the version now."""
    monkeypatch.setitem(VERSIONS, "world", 1)


def test_every_block_is_tied_or_listed_and_the_readme_quotes_none_stale(monkeypatch):
    monkeypatch.undo()  # the real versions
    blocks, problems = measured.check()
    assert blocks, "no measured block found"
    assert not problems, "\n".join(problems)
    unsettled = [block for block in blocks if block.state != "current"]
    if unsettled:
        warnings.warn("measured blocks not current:\n" + measured.listing(unsettled), stacklevel=1)


def _repository(tmp_path: Path, readme: str, not_tied: str = "", code: dict | None = None) -> Path:
    (tmp_path / "docs").mkdir()
    (tmp_path / "benchmarks").mkdir()
    (tmp_path / "README.md").write_text(readme)
    (tmp_path / "benchmarks" / "measured_not_tied.yaml").write_text(not_tied)
    _write_run(tmp_path, code or {})
    return tmp_path


def _write_run(root: Path, code: dict, command: str = PROVENANCE["command"]) -> None:
    """run.json, its provenance's ``stsf_gym`` updated with ``code``."""
    made_by = {**PROVENANCE, "command": command, "stsf_gym": {**PROVENANCE["stsf_gym"], **code}}
    (root / "run.json").write_text(json.dumps({"provenance": made_by}))


def _block(name: str, body: str, results: str = "") -> str:
    tie = f" results: {results}" if results else ""
    return f"<!-- measured: {name} (begin){tie} -->\n{body}\n<!-- measured: {name} (end) -->\n"


SHOWN = "`stsf-gym demo --seeds 1` at `0123abcd`"


@pytest.mark.parametrize(
    ("readme", "not_tied", "world", "problem"),
    [
        (_block("a", SHOWN, "run.json"), "", 1, None),
        (_block("a", SHOWN, "run.json"), "", 2, "README.md quotes 'a', which is stale"),
        (_block("a", "0.5 m", "run.json"), "", 1, "does not show run.json's"),
        (_block("a", SHOWN, "gone.json"), "", 1, "gone.json does not exist"),
        (_block("a", "0.5 m"), "", 1, "'a' names no results and"),
        (_block("a", "0.5 m"), "a: not kept", 1, "README.md quotes 'a', which is not tied"),
        (_block("a", SHOWN, "run.json"), "b: gone", 1, "lists 'b', which is no block"),
        ("<!-- measured: a (begin) -->\n0.5 m\n", "a: x", 1, "'a' never ends"),
    ],
)
def test_the_rules_on_a_small_repository(tmp_path, monkeypatch, readme, not_tied, world, problem):
    root = _repository(tmp_path, readme, not_tied)
    monkeypatch.setitem(VERSIONS, "world", world)
    blocks, problems = measured.check(root)
    if problem is None:
        assert not problems and [b.state for b in blocks] == ["current"]
    else:
        assert any(problem in p for p in problems), problems


def test_an_untied_page_block_is_listed_with_its_reason(tmp_path):
    root = _repository(tmp_path, "# no figures\n", "a: its results were not kept")
    (root / "docs" / "page.md").write_text(_block("a", "0.5 m"))
    blocks, problems = measured.check(root)
    assert not problems
    assert "its results were not kept" in measured.listing(blocks)


def _page_block(tmp_path: Path, code: dict, command: str = PROVENANCE["command"]) -> Path:
    """A repository whose docs page quotes run.json, made by ``code`` with ``command``."""
    root = _repository(tmp_path, "# no figures\n")
    _write_run(root, code, command)
    (root / "docs" / "page.md").write_text(_block("a", f"`{command}` at `0123abcd`", "run.json"))
    return root


def test_a_new_version_of_a_subsystem_the_run_used_makes_it_stale_and_names_it(
    tmp_path, monkeypatch
):
    root = _page_block(tmp_path, {"behaviour": {"world": 1, "scoring": VERSIONS["scoring"]}})
    (block,), _ = measured.check(root)
    assert block.state == "current"
    monkeypatch.setitem(VERSIONS, "learner", VERSIONS["learner"] + 1)  # a subsystem not used
    (block,), _ = measured.check(root)
    assert block.state == "current"
    monkeypatch.setitem(VERSIONS, "world", 2)
    (block,), _ = measured.check(root)
    assert block.state == "stale" and block.notes == ["run.json: behaviour changed: world v1 -> v2"]


def test_a_results_file_without_versions_is_stale(tmp_path):
    code = {k: v for k, v in PROVENANCE["stsf_gym"].items() if k != "behaviour"}
    root = _page_block(tmp_path, {})
    (root / "run.json").write_text(json.dumps({"provenance": {**PROVENANCE, "stsf_gym": code}}))
    (block,), _ = measured.check(root)
    assert block.state == "stale" and "made before results recorded behaviour" in block.notes[0]


def test_timings_go_stale_when_what_the_code_computes_changes_not_its_words(tmp_path):
    root = tmp_path
    (root / "envs").mkdir()
    module = root / "envs" / "m.py"
    module.write_text('"""A module."""\nX = 1  # one\n')
    command = "stsf-gym bench --out OUT"
    _page_block(root, {"timed_code": {"envs/m.py": code_digest(module)}}, command)
    module.write_text('"""A module, said better."""\n\nX = 1  # the number one\n')
    (block,), _ = measured.check(root)
    assert block.state == "current"
    module.write_text('"""A module."""\nX = 2\n')
    (block,), _ = measured.check(root)
    assert block.state == "stale"
    assert "timings of code that has changed: envs/m.py" in block.notes[0]


@pytest.mark.parametrize("recorded", [False, True])
def test_a_run_of_a_shipped_agent_is_current_only_with_its_models_recorded(tmp_path, recorded):
    command = "stsf-gym demo --seeds 1 --agents follower,pretrained:sparse/ppo-truth"
    models = tmp_path / "agents" / "pretrained" / "trained-models" / "sparse" / "ppo-truth"
    models.mkdir(parents=True)
    (models / "seed-0.zip").write_bytes(b"the policy")
    path = "agents/pretrained/trained-models/sparse/ppo-truth/seed-0.zip"
    loaded = {path: file_digest(tmp_path / path)} if recorded else {}
    root = _page_block(tmp_path, {"loaded_code": loaded}, command)
    (block,), _ = measured.check(root)
    assert block.state == ("current" if recorded else "stale")
    if not recorded:
        assert "pretrained:sparse/ppo-truth without recording" in block.notes[0]
    (models / "seed-0.zip").write_bytes(b"trained again")  # a new agent shipped under the name
    (block,), _ = measured.check(root)
    assert block.state == "stale"


def test_a_shipped_agent_renamed_keeps_its_results_current_under_its_alias(tmp_path):
    """Models moved to the agent's new name (``aliases.json``: old -> new) are the same models;
    the run that loaded them under the old name stays current, until they are shipped again."""
    command = "stsf-gym demo --seeds 1 --agents follower,pretrained:sparse/ppo-truth"
    shipped = tmp_path / "agents" / "pretrained" / "trained-models"
    (shipped / "sparse" / "ppo-truth").mkdir(parents=True)
    (shipped / "sparse" / "ppo-truth" / "seed-0.zip").write_bytes(b"the policy")
    old = "agents/pretrained/trained-models/sparse/ppo-truth/seed-0.zip"
    root = _page_block(tmp_path, {"loaded_code": {old: file_digest(tmp_path / old)}}, command)
    (shipped / "sparse" / "ppo-truth").rename(shipped / "sparse" / "dagger-truth")
    (block,), _ = measured.check(root)
    assert block.state == "stale"  # gone, and no alias says where
    (shipped / "aliases.json").write_text(json.dumps({"sparse/ppo-truth": "sparse/dagger-truth"}))
    (block,), _ = measured.check(root)
    assert block.state == "current"
    (shipped / "sparse" / "dagger-truth" / "seed-0.zip").write_bytes(b"trained again")
    (block,), _ = measured.check(root)
    assert block.state == "stale"
