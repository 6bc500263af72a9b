"""Saved results checked as they are read: an episode or a cell edited by hand fails its own
check and is recomputed, naming what failed; JSON files hold no NaN; a full disk is one line and
every file saved before stays valid."""

from __future__ import annotations

import numpy as np
import pytest

RADIUS = {"env": {"task": {"goal_radius": 0.25}}}


def stop(distance: float, success: bool) -> dict:
    return {"goal": 0, "time": 1.0, "position": [0.0, 0.0], "true_distance_m": distance,
            "success": success}  # fmt: skip


@pytest.mark.parametrize(
    ("result", "said"),
    [
        ([1, 2], "its result is a list, not a mapping"),
        ({"finite": True, "estimates": [[0.0, float("nan"), 0.0]]}, "estimates[0][1] holds nan"),
        ({"finite": True, "stops": [stop(5.0, True)]}, "stops[0] is marked a success 5 m from"),
        ({"finite": True, "stops": [stop(0.1, False)]}, "stops[0] is marked a miss 0.1 m from"),
    ],
)
def test_an_episode_edited_by_hand_fails_its_own_check(result, said):
    from stsf_gym.experiments.jobs.checks import episode_problem

    assert said in episode_problem(result, RADIUS)


def test_an_episode_as_the_code_writes_it_passes_its_check():
    from stsf_gym.experiments.jobs.checks import cell_problem, episode_problem

    diverged = {"finite": False, "estimates": [[float("nan")] * 3], "stops": [stop(0.1, True)]}
    assert episode_problem(diverged, RADIUS) is None
    cell = {"outcome": "goal", "metrics": {"nis_mean": None}, "navigation": {"stops": []}}
    assert cell_problem(cell, RADIUS) is None
    assert "result['metrics']['ate_rmse_m'] holds nan" in cell_problem(
        {**cell, "metrics": {"ate_rmse_m": float("nan")}}, RADIUS
    )


def test_a_saved_result_that_fails_its_check_is_recomputed_and_named(tmp_path, capsys):
    import sqlite3

    from stsf_gym.experiments.jobs.cache import run_cached
    from stsf_gym.experiments.jobs.checks import cell_problem
    from stsf_gym.experiments.jobs.spec import Finished

    def runner(fn, jobs):
        return ((job, Finished(fn(job), ["stsf_gym/metrics.py"])) for job in jobs)

    def run(job: dict) -> dict:
        return {"outcome": "goal", "navigation": {"stops": [stop(0.1, True)]}}

    def stored() -> str:
        with sqlite3.connect(store) as db:
            return db.execute("SELECT result FROM results WHERE key = 'cell'").fetchone()[0]

    store = tmp_path / "cells.sqlite"
    jobs = [{"seed": 0}]
    args = (jobs, store, lambda job: "cell", runner, "cells", lambda job: RADIUS)
    run_cached(run, *args, check=cell_problem)
    edited = stored().replace("0.1", "5.0")  # a stop 5 m off, marked a success, by hand
    with sqlite3.connect(store) as db:
        db.execute("UPDATE results SET result = ? WHERE key = 'cell'", (edited,))
    assert run_cached(run, *args, check=cell_problem) == [run({})]
    err = capsys.readouterr().err
    assert "1 saved result(s) in" in err and "fail their own check" in err
    assert "(e.g. cell: stops[0] is marked a success 5 m from its goal" in err
    assert '"true_distance_m": 0.1' in stored()  # recomputed


def test_json_files_hold_no_nan(tmp_path):
    import json

    from stsf_gym.io import write_json

    path = write_json(tmp_path / "results.json", {"ate": float("nan"), "v": np.array([np.inf, 1])})
    assert "NaN" not in path.read_text() and "Infinity" not in path.read_text()
    assert json.loads(path.read_text()) == {"ate": None, "v": [None, 1.0]}


def test_a_full_disk_is_one_line_saying_what_was_saved_stays_valid(run_cli, tmp_path, monkeypatch):
    import errno
    import os

    def full(src, dst):
        raise OSError(errno.ENOSPC, "No space left on device", str(dst))

    monkeypatch.setattr(os, "replace", full)
    out = tmp_path / "world.yaml"
    code, err = run_cli("world", "--seed", "1", "--out", str(out))
    assert code == 1 and len(err.strip().splitlines()) == 1
    assert f"the disk is full writing {out}; every file saved before stays valid" in err
    assert list(tmp_path.iterdir()) == []  # the temporary file is gone too
