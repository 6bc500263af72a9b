"""Figures that cannot go stale unseen: every measured block of README.md and docs/ is tied to
the results it quotes (command and code digest shown) or listed with the reason it is not; the
stale and untied ones are listed (a warning) on every run, and the README quotes none; a block
goes stale when code its results' run loaded changes, not any code
(``benchmarks/measured_blocks.py``)."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from stsf_gym.results.provenance import file_digest

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


def _write_run(root: Path, loaded: dict[str, str], commit: str | None = None) -> None:
    """run.json, its provenance listing the code its run ``loaded`` (``{path: digest}``)."""
    code = {**PROVENANCE["stsf_gym"], "loaded_code": loaded, "commit": commit}
    (root / "run.json").write_text(json.dumps({"provenance": {**PROVENANCE, "stsf_gym": code}}))


LOADED = ("envs/m0.py", "envs/m1.py")  # of the small repository's three modules


def _loaded_repository(tmp_path: Path) -> Path:
    """A repository of three modules whose run.json lists the first two as loaded by its run."""
    root = _repository(tmp_path, _block("a", SHOWN, "run.json"))
    (root / "envs").mkdir()
    for n in range(3):
        (root / "envs" / f"m{n}.py").write_text(f"X = {n}\n")
    _write_run(root, {path: file_digest(root / path) for path in LOADED})
    return root


def test_a_block_whose_loaded_code_is_unchanged_is_current_whatever_else_changed(tmp_path):
    root = _loaded_repository(tmp_path)
    (root / "envs" / "m2.py").write_text("X = 'edited, never loaded by the run'\n")
    blocks, problems = measured.check(root, "ffff0000")  # the whole digest differs
    assert not problems and [b.state for b in blocks] == ["current"]


@pytest.mark.parametrize("change", ["edit", "delete"])
def test_a_change_to_loaded_code_makes_the_block_stale_and_names_the_file(tmp_path, change):
    root = _loaded_repository(tmp_path)
    module = root / "envs" / "m1.py"
    if change == "edit":
        module.write_text("X = 'edited'\n")
    else:
        module.unlink()
    blocks, problems = measured.check(root, "0123abcd")  # the whole digest is the same
    assert problems == ["README.md quotes 'a', which is stale"]
    assert blocks[0].notes == [
        "run.json: 1 of the 2 files its run loaded changed (envs/m1.py), "
        "the run recorded no commit (its code was no git checkout)"
    ]


def test_a_note_counts_the_commits_that_changed_the_loaded_files(tmp_path):
    root = _loaded_repository(tmp_path)

    def commit(message: str) -> str:
        git = ["git", "-c", "user.name=t", "-c", "user.email=t@t"]
        subprocess.run([*git, "add", "-A"], cwd=root, check=True)
        subprocess.run([*git, "commit", "-qm", message], cwd=root, check=True)
        head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=root, capture_output=True)
        return head.stdout.decode().strip()

    subprocess.run(["git", "init", "-q"], cwd=root, check=True)
    made_at = commit("the run's code")
    _write_run(root, {path: file_digest(root / path) for path in LOADED}, made_at)
    for n in (1, 2):  # m1, loaded by the run, and m2, never loaded, each edited and committed
        (root / "envs" / f"m{n}.py").write_text("X = 'edited'\n")
        commit(f"m{n} edited")
    (block,), _ = measured.check(root, "0123abcd")
    assert block.notes == [
        f"run.json: 1 of the 2 files its run loaded changed (envs/m1.py), made at commit "
        f"{made_at[:10]}; 1 later commits changed them"
    ]


def test_a_note_names_a_few_changed_files_and_counts_the_rest(tmp_path):
    root = _repository(tmp_path, _block("a", SHOWN, "run.json"))
    _write_run(root, {f"envs/m{n}.py": "0000" for n in range(5)})  # none of them there now
    (block,), _ = measured.check(root, "0123abcd")
    assert block.state == "stale"
    assert "5 of the 5 files" in block.notes[0]
    assert "(envs/m0.py, envs/m1.py, envs/m2.py and 2 more)" in block.notes[0]


OLD_NOTE = "run.json: digest 0123abcd, the run recorded no commit (its code was no git checkout)"


@pytest.mark.parametrize(
    ("digest", "state", "notes"), [("0123abcd", "current", []), ("ffff0000", "stale", [OLD_NOTE])]
)
def test_a_results_file_without_loaded_code_is_judged_by_the_whole_digest(
    tmp_path, digest, state, notes
):
    root = _repository(tmp_path, "# no figures\n")
    (root / "docs" / "page.md").write_text(_block("a", SHOWN, "run.json"))
    (block,), problems = measured.check(root, digest)
    assert not problems and (block.state, block.notes) == (state, notes)


def _rewrite(
    root: Path, before: str, proof: str = "tests/test_equal.py", changes: list | None = None
) -> None:
    """Record envs/m1.py's change from digest ``before`` to its bytes now as bit-exact (for
    every command but ``changes``)."""
    (root / "tests").mkdir(exist_ok=True)
    (root / "tests" / "test_equal.py").write_text("def test_equal(): pass\n")
    entry = {
        "path": "envs/m1.py",
        "before": before,
        "after": file_digest(root / "envs" / "m1.py"),
        "before_commit": "abc1234",
        "proof": [proof],
        **({"changes": changes} if changes else {}),
    }
    (root / "benchmarks" / "equivalent_code.yaml").write_text(json.dumps([entry]))


@pytest.mark.parametrize(
    ("command", "changed"),
    [
        ("stsf-gym demo --seeds 1", False),
        ("stsf-gym bench --out b", True),  # timings: every rewrite changes them
        ("stsf-gym train --suite s", True),  # named in the record's changes
        ("stsf-gym trainer", False),  # a prefix is whole words
    ],
)
def test_a_recorded_bit_exact_rewrite_keeps_results_current_but_not_the_commands_it_changes(
    tmp_path, command, changed
):
    root = _loaded_repository(tmp_path)
    before = file_digest(root / "envs" / "m1.py")
    (root / "envs" / "m1.py").write_text("X = 0 + 1  # the same number, other bytes\n")
    _rewrite(root, before, changes=["stsf-gym train"])
    run = json.loads((root / "run.json").read_text())
    run["provenance"]["command"] = command
    (root / "run.json").write_text(json.dumps(run))
    (root / "README.md").write_text(_block("a", f"`{command}` at `0123abcd`", "run.json"))
    blocks, problems = measured.check(root, "0123abcd")
    assert [b.state for b in blocks] == ["stale" if changed else "current"]
    assert problems == (["README.md quotes 'a', which is stale"] if changed else [])


def test_a_rewrite_from_other_bytes_or_without_a_test_proves_nothing(tmp_path):
    root = _loaded_repository(tmp_path)
    (root / "envs" / "m1.py").write_text("X = 0 + 1\n")
    _rewrite(root, "0000000000000000", proof="notes/believe-me.md")  # not the run's digest
    blocks, problems = measured.check(root, "0123abcd")
    assert blocks[0].state == "stale"
    assert any("proof notes/believe-me.md is no test file" in p for p in problems), problems


def test_recording_a_rewrite_takes_the_digests_from_head_and_the_file_now(tmp_path):
    root = _loaded_repository(tmp_path)
    (root / "tests").mkdir()
    (root / "tests" / "test_equal.py").write_text("def test_equal(): pass\n")
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@t", "-C", str(root)]
    subprocess.run([*git, "init", "-q"], check=True)
    subprocess.run([*git, "add", "-A"], check=True)
    subprocess.run([*git, "commit", "-qm", "x"], check=True)
    (root / "envs" / "m1.py").write_text("X = 0 + 1\n")
    measured.record_rewrite(["envs/m1.py"], "same X", ["tests/test_equal.py"], root, ["x y"])
    blocks, problems = measured.check(root, "0123abcd")
    assert not problems and blocks[0].state == "current"
    rewrites, _ = measured.equivalent_rewrites(root)
    assert [changes for _, changes in rewrites.values()] == [("stsf-gym bench", "x y")]


@pytest.mark.parametrize("recorded", [False, True])
def test_a_run_of_a_shipped_agent_is_current_only_with_its_models_recorded(tmp_path, recorded):
    root = _repository(tmp_path, _block("a", SHOWN, "run.json"))
    models = root / "agents" / "pretrained" / "trained-models" / "sparse" / "ppo-truth"
    models.mkdir(parents=True)
    (models / "seed-0.zip").write_bytes(b"the policy")
    loaded = {"agents/pretrained/trained-models/sparse/ppo-truth/seed-0.zip": "0000"}
    _write_run(root, {path: file_digest(root / path) for path in loaded} if recorded else {})
    run = json.loads((root / "run.json").read_text())
    run["provenance"]["command"] += " --agents follower,pretrained:sparse/ppo-truth"
    (root / "run.json").write_text(json.dumps(run))
    (block,), _ = measured.check(root, "0123abcd")
    assert block.state == ("current" if recorded else "stale")
    if not recorded:
        assert "pretrained:sparse/ppo-truth without recording" in block.notes[0]
    (models / "seed-0.zip").write_bytes(b"trained again")  # a new agent shipped under the name
    (block,), _ = measured.check(root, "0123abcd")
    assert block.state == "stale"
