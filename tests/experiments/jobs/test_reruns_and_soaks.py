"""Bad input gets a clear error; crashed jobs are rerun; long runs leak nothing; parallel runs
match serial ones. (Config ranges and geometry: tests/config/test_config.py.)"""

from __future__ import annotations

import os
import re
import sqlite3
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from helpers import load_script

from stsf_gym.experiments.jobs.cache import JobsFailed
from stsf_gym.experiments.jobs.engine import run_jobs
from stsf_gym.experiments.jobs.spec import JobKind
from stsf_gym.experiments.jobs.store import read_rows
from stsf_gym.validation import ConfigError, Positive, build

LIFETIME_CYCLES = 200  # 1000 in `benchmarks/soak.py --cycles 1000`; this many keep it < 1 min
SOAK_STEPS = 5000  # 200,000 in `benchmarks/soak.py --steps 200000`


def _soak_module():
    return load_script("benchmarks/soak.py")


# --- actions ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("action", "message"),
    [
        ([np.nan, 0.0], "NaN or infinite"),
        ([0.5, np.inf], "NaN or infinite"),
        ([0.5, 0.0, 0.1], r"shape \(2,\)"),
        ([[0.5, 0.0]], r"shape \(2,\), got \(1, 2\)"),  # a batch of one is not flattened
        (["0.5", "0.0"], "must be numeric"),
        (np.array([0.5, None], dtype=object), "must be numeric"),
        ([True, False], "must be numeric"),
        ("forward", "must be numeric"),
    ],
)
def test_bad_actions_raise_clear_errors(make_env, action, message):
    env = make_env(camera__enabled=False)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(action)


def test_out_of_range_actions_are_clipped(make_env):
    env = make_env(camera__enabled=False)
    poses = []
    for action in ([1.0, -1.0], [7.5, -30.0]):
        env.reset(seed=4)
        for _ in range(10):
            *_, info = env.step(np.float32(action))
        poses.append(info["true_pose"])
    np.testing.assert_array_equal(poses[0], poses[1])
    env.reset(seed=4)
    for _ in range(10):
        *_, info = env.step(np.float32([0.5, 0.0]))
    assert not np.array_equal(info["true_pose"], poses[0])  # the action does matter


# --- command line -------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["evaluate", "--estimators", "odometry,magic"], "unknown estimator 'magic'"),
        (["evaluate", "--agent", "path/that/does/not/exist.zip"], "path/that/does/not/exist.zip"),
        (["evaluate", "--set", "robot.wheel_radius=-1"], "robot.wheel_radius must be in (0, 10]"),
        (["evaluate", "--set", "world.start=[0,0,0]"], "use --world"),
        (["demo", "--set", "camera.width=0"], "camera.width must be in [1, 8192], got 0"),
        (["reproduce", "fig10", "--seeds", "0"], "--seeds must be at least 1"),
        (["train", "--seeds", "0"], "--seeds must be at least 1"),
        (["train", "--timesteps", "100"], "would end at 2048; ask for 2048"),
        (["benchmark", "--suite", "sparse", "--seed", "-1"], "--seed must be at least 0, got -1"),
        (
            ["benchmark", "--suite", "sparse", "--estimators", "stsf,ekf,stsf"],
            "'stsf' is named twice",
        ),
        (["evaluate", "--agent", "follower,follower"], "'follower' is named twice"),
        (["train", "--suite", "sparse", "--world", "straight_10m"], "drop --world/--split"),
        (["train", "--suite", "sparse", "--world", "irl_corridor"], "drop --world/--split"),
        (["train", "--world", "generated", "--split", "dev"], "split must be one of"),
        (["train", "--backend", "ray"], "--backend and --address are for a campaign"),
        (["train", "--estimators", "truth", "--workers", "0"], "--workers must be at least 1"),
        (["benchmark", "--suite", "sparse", "--agents", "no/such/folder"], "no/such/folder"),
        (
            ["train", "--suite", "corridor", "--set", "env.task.start_lateral=5"],
            "task.start_lateral 5 m across the path",
        ),
    ],
)
def test_cli_bad_input_exits_2_with_one_line_and_writes_nothing(run_cli, tmp_path, argv, message):
    out = tmp_path / "out"
    code, err = run_cli(*argv, "--out", str(out))
    command = argv[0]
    assert code == 2
    assert err.startswith(f"stsf-gym {command}: error: ") and message in err
    assert len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_cli_names_the_config_file_of_a_bad_value(run_cli, tmp_path):
    config = tmp_path / "bad.yaml"
    config.write_text("sonar:\n  dropout_prob: 2\n")
    code, err = run_cli("demo", "--config", str(config), "--out", str(tmp_path / "out"))
    assert code == 2 and f"{config}: sonar.dropout_prob must be in [0, 1], got 2" in err
    config.write_text("sonar: [unclosed\n")
    code, err = run_cli("demo", "--config", str(config), "--out", str(tmp_path / "out"))
    assert code == 2 and f"{config}: malformed YAML at line 2" in err


def test_cli_unwritable_out_fails_before_any_work(run_cli, tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    code, err = run_cli("evaluate", "--out", str(blocker / "results"))
    assert code == 2 and f"{blocker} is not a folder" in err
    assert blocker.read_text() == "not a folder"


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write into read-only folders")
def test_cli_read_only_out_fails_before_any_work(run_cli, tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o555)
    code, err = run_cli("evaluate", "--out", str(locked / "results"))
    assert code == 2 and "is not writable" in err
    assert list(locked.iterdir()) == []


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


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (  # a lens whose image folds over: no ray for the image corners
            ["evaluate", "--set", "camera.lens.distortion=[-3,0,0,0,0]"],
            "camera.lens.distortion .* folds the image over",
        ),
        (  # a landmark estimator on an env without a camera would run as odometry
            ["evaluate", "--estimators", "stsf", "--set", "camera.enabled=false"],
            "pose source 'stsf' reads the camera, but camera.enabled is false",
        ),
        (  # two options setting one value: neither may win silently
            ["demo", "--seconds", "5", "--set", "sim.max_episode_seconds=9"],
            "--seconds and sim.max_episode_seconds .* both set the episode length",
        ),
        (  # a number where a number is meant, not a boolean
            ["evaluate", "--set", "encoders.slip_std=true"],
            "encoders.slip_std must be a number, got True",
        ),
    ],
)
def test_meaningless_combinations_are_refused_before_any_work(run_cli, tmp_path, argv, message):
    out = tmp_path / "out"
    code, err = run_cli(*argv, "--out", str(out))
    assert code == 2 and re.search(message, err), err
    assert "Traceback" not in err and not out.exists()


def test_a_fault_that_could_never_act_is_refused(tmp_path, run_cli):
    faults = tmp_path / "late.yaml"
    faults.write_text("faults:\n  - {kind: kidnap, start: 500.0, shift: [0.3, 0.1], turn_deg: 8}\n")
    code, err = run_cli("evaluate", "--faults", str(faults), "--out", str(tmp_path / "out"))
    assert code == 2 and "late.yaml" in err
    assert "faults[0].start must be before the episode ends" in err


def test_a_generator_that_can_never_make_a_world_names_why(tmp_path):
    from stsf_gym.envs.config import load_config
    from stsf_gym.envs.worlds.generator import generate_world
    from stsf_gym.envs.worlds.generator_config import load_generator_config

    long = tmp_path / "long.yaml"
    long.write_text("min_path_length: 100\n")
    with pytest.raises(ConfigError, match=r"long\.yaml: generator\.min_path_length can never"):
        load_generator_config(long)
    narrow = load_generator_config({"width": [0.3, 0.4]})
    with pytest.raises(ConfigError, match=r"generator\.width .* narrower than the robot needs"):
        generate_world(1, narrow, load_config())


@dataclass(frozen=True)
class OptionalLimit:
    """A setting typed ``X | None``: each member of the union is checked."""

    limit: Positive | None = None


def test_a_union_typed_setting_checks_each_member():
    assert build(OptionalLimit, {"limit": None}, "x").limit is None
    assert build(OptionalLimit, {"limit": 2}, "x").limit == 2.0
    with pytest.raises(ConfigError, match=r"x\.limit must be a number, got True"):
        build(OptionalLimit, {"limit": True}, "x")
    with pytest.raises(ConfigError, match=r"x\.limit must be > 0, got -1"):
        build(OptionalLimit, {"limit": -1}, "x")
