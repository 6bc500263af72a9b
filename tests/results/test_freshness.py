"""Freshness is derived from the code each job ran with (:mod:`stsf_gym.results.freshness`): a
scoring change recomputes the stored jobs that loaded the changed module and no others, a
rewrite that leaves what a module computes (its docstrings) recomputes nothing, and the only
declared override names modules the golden episodes pin."""

from __future__ import annotations

import pytest
from helpers import load_script

import stsf_gym.results.freshness as freshness
from stsf_gym.experiments.jobs.cache import run_cached
from stsf_gym.experiments.jobs.spec import Finished
from stsf_gym.experiments.jobs.store import read_rows
from stsf_gym.results.behaviour import subsystem
from stsf_gym.results.code_identity import package_file

#: The modules each kind of job loads: an episode scored in its worker, a Table I seed.
MODULES = {
    "episode": ["envs/robot.py", "stsf_gym/metrics.py", "stsf_gym/estimators/ekf.py"],
    "seed": ["envs/robot.py", "stsf_gym/experiments/table1/measure.py"],
}
JOBS = [{"kind": kind, "n": n} for kind in MODULES for n in range(3)]


def _key(job: dict) -> str:
    return f"{job['kind']}-{job['n']}"


def _run(store, calls: list) -> list:
    def runner(fn, jobs):
        for job in jobs:
            yield job, Finished(fn(job), MODULES[job["kind"]])

    def fn(job: dict) -> dict:
        calls.append(_key(job))
        return {"value": job["n"]}

    return run_cached(fn, JOBS, store, _key, runner, desc="", config=lambda job: {"k": 1})


def _edited(monkeypatch, name: str) -> None:
    """Make the module file ``name`` compute otherwise, as an edit on a branch would."""
    digest = freshness.code_digest
    monkeypatch.setattr(
        freshness, "code_digest", lambda file: "edited" if file.name == name else digest(file)
    )


def test_a_scoring_change_recomputes_the_jobs_that_loaded_it_and_no_others(tmp_path, monkeypatch):
    store, calls = tmp_path / "cells.sqlite", []
    first = _run(store, calls)
    assert len(calls) == 6 and first == [{"value": job["n"]} for job in JOBS]
    codes = {key: row.code for key, row in read_rows(store).items()}
    assert set(codes["episode-0"]) == set(MODULES["episode"])  # each job's own code recorded

    calls.clear()
    assert _run(store, calls) == first and calls == []  # unchanged: nothing recomputed

    _edited(monkeypatch, "metrics.py")  # a scoring change
    assert _run(store, calls) == first
    assert calls == ["episode-0", "episode-1", "episode-2"]  # the episodes only
    calls.clear()
    assert _run(store, calls) == first and calls == []  # stored again, under the new code


def test_another_config_recomputes_and_says_so(tmp_path, capsys):
    store, calls = tmp_path / "cells.sqlite", []
    _run(store, calls)
    calls.clear()

    def runner(fn, jobs):
        for job in jobs:
            yield job, Finished(fn(job), MODULES[job["kind"]])

    run_cached(lambda job: calls.append(job) or {}, JOBS[:1], store, _key, runner, "jobs", None)
    assert len(calls) == 1 and "made by other code or settings" in capsys.readouterr().err


def test_a_reworded_module_computes_the_same(tmp_path):
    reworded = tmp_path / "metrics.py"
    text = package_file("stsf_gym/metrics.py").read_text()
    reworded.write_text(text.replace('"""', '"""Reworded. ', 1) + "# a comment\n")
    assert freshness.code_digest(reworded) == freshness.code_digest(
        package_file("stsf_gym/metrics.py")
    )


def test_an_equivalent_rewrite_is_declared_only_where_the_goldens_prove_it(monkeypatch):
    current = freshness.CurrentCode()
    record = {"envs/robot.py": "an-earlier-digest"}
    assert not current.is_current(record)
    monkeypatch.setitem(freshness.EQUIVALENT, "envs/robot.py", frozenset({"an-earlier-digest"}))
    assert current.is_current(record)
    assert not current.is_current({})  # a job that recorded no code is never current


@pytest.mark.parametrize("path", sorted(freshness.EQUIVALENT) or ["none declared"])
def test_each_declared_equivalence_is_pinned_by_the_golden_episodes(path):
    pinned = load_script("tests/behaviour/test_step_equality.py").PINNED
    assert path == "none declared" or subsystem(path) in pinned
