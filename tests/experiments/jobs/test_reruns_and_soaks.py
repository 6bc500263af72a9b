"""Crashed jobs are reported and rerun, a job failing twice keeps the others; long runs leak
nothing; parallel runs match serial ones to the bit. (Bad input: tests/cli/test_bad_input.py and
tests/envs/test_env_inputs.py.)"""

from __future__ import annotations

import os
import sqlite3
from contextlib import closing
from pathlib import Path

import pytest
from helpers import load_script

from stsf_gym.experiments.jobs.cache import JobsFailed
from stsf_gym.experiments.jobs.engine import run_jobs
from stsf_gym.experiments.jobs.spec import JobKind
from stsf_gym.experiments.jobs.store import read_rows

LIFETIME_CYCLES = 200  # 1000 in `benchmarks/soak.py --cycles 1000`; this many keep it < 1 min
SOAK_STEPS = 5000  # 200,000 in `benchmarks/soak.py --steps 200000`


def _soak_module():
    return load_script("benchmarks/soak.py")


# --- crashed jobs -------------------------------------------------------------------------


def flaky_job(job: dict) -> dict:
    """Fails the first time it runs a job marked ``crash`` (raising, or killing its process),
    using a marker file to know; ``crash: "always"`` kills its process every time."""
    marker = Path(job["marker"])
    first_time = not marker.exists()
    marker.touch()
    if job["crash"] == "always" or (first_time and job["crash"] == "exit"):
        os._exit(3)
    if first_time and job["crash"] == "raise":
        raise RuntimeError(f"job {job['n']} fails once")
    runs = Path(f"{job['marker']}.runs")
    runs.write_text(runs.read_text() + "x" if runs.exists() else "x")
    return {"double": 2 * job["n"]}


def _jobs(tmp_path: Path, crashes: dict[int, str]) -> list[dict]:
    return [
        {"n": n, "crash": crashes.get(n, ""), "marker": str(tmp_path / f"marker{n}")}
        for n in range(5)
    ]


def _name(job: dict) -> str:
    return f"job{job['n']}"


FLAKY = JobKind(flaky_job, _name)


@pytest.mark.slow
@pytest.mark.parametrize("workers", [1, 2])
def test_crashed_jobs_are_reported_and_rerun(tmp_path, capsys, workers):
    crashes = {1: "raise"} if workers == 1 else {1: "raise", 3: "exit"}
    ran = run_jobs(FLAKY, _jobs(tmp_path, crashes), tmp_path / "out", workers=workers)
    assert ran.results == [{"double": 2 * n} for n in range(5)]
    err = capsys.readouterr().err
    assert "job1 failed: RuntimeError: job 1 fails once; running it again" in err
    if workers > 1:
        assert "job3 failed: the worker process died" in err
    assert "job0 failed" not in err and "job2 failed" not in err  # bystanders are not blamed
    assert all((tmp_path / f"marker{n}.runs").read_text() == "x" for n in range(5))


@pytest.mark.slow
def test_job_failing_twice_keeps_the_others_and_a_rerun_resumes(tmp_path, capsys):
    out = tmp_path / "out"
    with pytest.raises(JobsFailed, match="job2: the worker process died") as failed:
        run_jobs(FLAKY, _jobs(tmp_path, {2: "always"}), out, workers=2)
    assert list(failed.value.failures) == ["job2"]
    assert "job2 failed: the worker process died" in capsys.readouterr().err
    assert sorted(read_rows(out)) == [f"job{n}" for n in (0, 1, 3, 4)]
    with closing(sqlite3.connect(out)) as db, db:  # a row of another job: redone, not trusted
        db.execute("UPDATE results SET job = '{\"n\": 40}' WHERE key = 'job4'")
    ran = run_jobs(FLAKY, _jobs(tmp_path, {}), out, workers=2)
    assert ran.results == [{"double": 2 * n} for n in range(5)]
    runs = [(tmp_path / f"marker{n}.runs").read_text() for n in range(5)]
    assert runs == ["x", "x", "x", "x", "xx"]  # only the failed and the corrupt job ran again


# --- long runs and many envs --------------------------------------------------------------


@pytest.mark.slow
def test_env_lifetimes_leak_no_clients_bodies_or_memory():
    soak = _soak_module()
    report = soak.cycle_envs(LIFETIME_CYCLES)
    assert report["clients_left_connected"] == 0
    assert len(report["bodies_per_client"]) == 1  # every new client holds the same bodies
    assert len(report["client_ids"]) == 1  # a closed client's slot is reused
    assert report["rss_growth_mb"] < soak.MAX_RSS_GROWTH_MB
    assert soak.failures({"cycles": report}) == []


@pytest.mark.slow
def test_parallel_soak_matches_serial_bit_for_bit():
    soak = _soak_module()
    report = soak.soak(SOAK_STEPS, workers=2, seed=3)
    assert report["steps"] >= SOAK_STEPS
    assert report["parallel"]["episodes"] > 0  # episodes ended and auto-reset in the soak
    assert report["parallel"]["sha256"] == report["serial"]["sha256"]
    assert report["parallel"]["episodes"] == report["serial"]["episodes"]
    assert soak.failures(report) == []


def _renderers_here() -> list[str]:
    """TinyRenderer, and those of the OpenGL renderers that start on this machine."""
    from stsf_gym.envs.simulator import Simulator

    here = ["tiny"]
    for renderer in ("egl", "gl"):
        try:
            Simulator(60.0, renderer).close()
            here.append(renderer)
        except RuntimeError:
            pass
    return here


@pytest.mark.slow
def test_images_are_bit_identical_per_renderer_serial_and_parallel():
    """Each renderer repeats itself exactly (here and in forkserver workers); the renderers
    rasterise differently, so their images differ."""
    soak = _soak_module()
    renderers = _renderers_here()
    camera = {"camera__width": 64, "camera__height": 48, "camera__profile": "ideal"}
    hashes = {}
    for renderer in renderers:
        report = soak.soak(60, 2, seed=1, env_kwargs={**camera, "camera__renderer": renderer})
        assert report["parallel"]["renderers"] == report["serial"]["renderers"] == [renderer]
        assert report["parallel"]["sha256"] == report["serial"]["sha256"], renderer
        hashes[renderer] = report["serial"]["sha256"]
    assert len(set(hashes.values())) == len(renderers)
