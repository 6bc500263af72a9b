"""A full disk (``OSError`` ``ENOSPC``) met by a job, in this process or a worker process,
stops the run at once with that error (no retry, no "failed twice"): the command line's one
line; the results stored before stay valid and a rerun resumes from them."""

from __future__ import annotations

import errno
from pathlib import Path

import pytest

from stsf_gym.experiments.jobs import cells
from stsf_gym.experiments.jobs.engine import run_jobs
from stsf_gym.experiments.jobs.spec import JobKind
from stsf_gym.experiments.jobs.store import read_rows

NO_SPACE = "No space left on device"


def fills_the_disk(job: dict) -> dict:
    """Job ``n`` (its run counted in a marker file); job 2 meets a full disk while the file
    ``job["full"]`` exists."""
    if job["n"] == 2 and Path(job["full"]).exists():
        raise OSError(errno.ENOSPC, NO_SPACE, job["full"])
    runs = Path(f"{job['marker']}.runs")
    runs.write_text(runs.read_text() + "x" if runs.exists() else "x")
    return {"double": 2 * job["n"]}


FILLS = JobKind(fills_the_disk, lambda job: f"job{job['n']}")


@pytest.mark.parametrize("workers", [1, pytest.param(2, marks=pytest.mark.slow)])
def test_a_full_disk_stops_the_run_and_a_rerun_resumes(tmp_path, capsys, workers):
    full, out = tmp_path / "full", tmp_path / "out.sqlite"
    full.touch()
    jobs = [{"n": n, "full": str(full), "marker": str(tmp_path / f"job{n}")} for n in range(5)]
    with pytest.raises(OSError, match=NO_SPACE) as raised:
        run_jobs(FILLS, jobs, out, workers=workers)
    assert raised.value.errno == errno.ENOSPC and raised.value.filename == str(full)
    assert "failed" not in capsys.readouterr().err  # not retried, not reported as a job's bug
    stored = read_rows(out)
    assert "job2" not in stored
    assert all(row.result == {"double": 2 * int(key[3:])} for key, row in stored.items())
    full.unlink()  # space freed: the rerun runs what was not stored, and only that
    assert run_jobs(FILLS, jobs, out, workers=workers).results == [
        {"double": 2 * n} for n in range(5)
    ]
    for key in stored:
        assert (tmp_path / f"{key}.runs").read_text() == "x"


def test_a_sweep_cell_raises_a_full_disk_and_keeps_other_errors(monkeypatch):
    def fails(error: Exception):
        def run(cell: dict) -> dict:
            raise error

        return cells.CellKind(run)

    monkeypatch.setitem(cells.CELL_KINDS, "evaluate", fails(OSError(errno.ENOSPC, NO_SPACE)))
    with pytest.raises(OSError, match=NO_SPACE):
        cells.run_cell({"kind": "evaluate"})
    monkeypatch.setitem(cells.CELL_KINDS, "evaluate", fails(ValueError("a bug")))
    assert cells.run_cell({"kind": "evaluate"})["error"] == "ValueError: a bug"


@pytest.mark.parametrize(
    "argv",
    [
        ["evaluate", "--seeds", "2"],
        ["benchmark", "--suite", "corridor", "--worlds", "1", "--agents", "follower"],
    ],
)
def test_a_full_disk_under_an_episode_command_is_one_line(run_cli, tmp_path, monkeypatch, argv):
    import stsf_gym.experiments.episodes as episodes

    written = tmp_path / "out" / "recording.mcap"

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, NO_SPACE, str(written))

    monkeypatch.setattr(episodes, "run_episode", full)
    code, err = run_cli(
        *argv, "--workers", "1", "--estimators", "truth", "--out", str(tmp_path / "out")
    )
    errors = [line for line in err.splitlines() if "error:" in line]
    assert code == 1 and errors == [err.strip().splitlines()[-1]], err
    assert f"the disk is full writing {written}; every file saved before stays valid" in errors[0]
    assert "rerun with the same --out to resume" in errors[0]
    assert "Traceback" not in err and "failed" not in err
