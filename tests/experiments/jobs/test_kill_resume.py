"""Nothing lost on a kill: every long command (the paper's figures, the accuracy curve, sweeps,
the benchmark and training), SIGKILLed with its worker processes mid-run and then run again
with the same arguments, finishes with the results of an uninterrupted run (timing fields and
provenance aside), recomputes none of the units that had finished, and leaves no file that
cannot be read."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from helpers import ROOT

from stsf_gym.experiments.jobs.store import read_rows

CLI = [sys.executable, "-m", "stsf_gym.cli"]
FAST = ["--set", "camera.mode=fast", "--set", "sim.max_episode_seconds=20"]
#: Keys whose values are wall-clock measurements or depend on where the run was written.
TIMING = {
    "provenance",
    "ms_per_step",
    "stage_ms_per_step",
    "wall_time_s",
    "session_wall_time_s",
    "steps_per_second",
    "figures",
    "figure",
    "machine",  # the reference workload and load average, read at each run's start
}
SWEEP = {
    "base": {
        "world": "straight_10m",
        "env": {"camera": {"mode": "fast"}, "sim": {"max_episode_seconds": 15.0}},
    },
    "grid": {"estimator": ["odometry", "ekf"], "env.encoders.slip_std": [0.01, 0.03], "seeds": 1},
}
CURVE = "accuracy-curve --agent follower --world straight_10m --seeds 1 --levels 1,4"
TRAIN = "train --algo ppo --estimator truth --timesteps 640 --n-envs 1 --set n_steps=64"
TRAIN += " --set batch_size=32 --set checkpoint_freq=128 --set eval_freq=100000"
CAMPAIGN = "train --suite corridor --estimators truth,odometry --seeds 1 --n-envs 1"
CAMPAIGN += " --set demonstrations.expert_episodes=1 --set demonstrations.rounds=0"
CAMPAIGN += " --set n_eval_episodes=1 --set env.sim.max_episode_seconds=10"
FINETUNE = "train --suite corridor --estimator truth --algo dagger+ppo --n-envs 1"
FINETUNE += " --set demonstrations.expert_episodes=1 --set demonstrations.rounds=0"
FINETUNE += " --set demonstrations.cloning.epochs=2 --set n_eval_episodes=1 --set eval_freq=64"
FINETUNE += " --set checkpoint_freq=32 --set n_steps=32 --set batch_size=32 --set n_epochs=2"
FINETUNE += " --set env.sim.max_episode_seconds=6 --set train_env.sim.max_episode_seconds=6"
FINETUNE += " --set finetune.timesteps=192 --set finetune.value_warmup_steps=32"
#: command (after ``stsf-gym``), where it saves its units as they finish (under --out): a
#: store (its rows) or a glob (its files)
COMMANDS = {
    "fig10": (
        [*"reproduce fig10 --seeds 2 --workers 2".split(), *FAST],
        "fig10/episodes/episodes.sqlite",
    ),
    "fig11": (
        [*"reproduce fig11 --seeds 1 --workers 2".split(), *FAST],
        "fig11/episodes/episodes.sqlite",
    ),
    "table1": (
        "reproduce table1 --seeds 3 --workers 1 --set frames_per_place=2".split(),
        "table1/seeds.sqlite",
    ),
    "accuracy-curve": (
        [*CURVE.split(), "--estimators", "odometry", "--workers", "2", *FAST],
        "cells.sqlite",
    ),
    "sweep": ("sweep {sweep} --workers 2".split(), "tiny/cells.sqlite"),
    "benchmark": (  # on the true pose: each route ends at its goal (odometry's may not)
        "benchmark --suite corridor --worlds 3 --estimators truth --workers 2".split(),
        "corridor/cells.sqlite",
    ),
    "train": (
        [*TRAIN.split(), "--set", "env.sim.max_episode_seconds=3"],
        "checkpoints/model_*_steps.zip",
    ),
    "finetune": (FINETUNE.split(), "checkpoints/model_*_steps.zip"),  # killed in the PPO stage
    "campaign": (  # two runs of the learner, tiny: one expert leg, no DAgger round, 1 val route
        [*CAMPAIGN.split(), "--set", "train_env.sim.max_episode_seconds=8"],
        "*/seed-0/train.json",
    ),
}


def _argv(name: str, out: Path, folder: Path) -> list[str]:
    argv, _ = COMMANDS[name]
    sweep = folder / "tiny.yaml"
    sweep.write_text(yaml.safe_dump(SWEEP))
    return [*CLI, *[a.format(sweep=sweep) for a in argv], "--out", str(out), "--json"]


def _finish(argv: list[str]) -> dict:
    done = subprocess.run(argv, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout)


def _units(out: Path, pattern: str) -> dict[str, int]:
    """``{unit: when it was written}`` of the saved units: rows of a store, or files."""
    if pattern.endswith(".sqlite"):
        try:
            return {key: row.written_ns for key, row in read_rows(out / pattern).items()}
        except sqlite3.OperationalError:  # being written: not yet
            return {}
    return {str(unit): unit.stat().st_mtime_ns for unit in sorted(out.glob(pattern))}


def _kill_after_first_unit(argv: list[str], pattern: str, out: Path) -> dict[str, int]:
    """Start the command in its own process group; SIGKILL the group once a unit is saved;
    return the units saved by then."""
    run = subprocess.Popen(
        argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
    )
    deadline = time.monotonic() + 300
    while not _units(out, pattern):
        assert run.poll() is None, "the command finished before it could be killed"
        assert time.monotonic() < deadline, "no unit saved in 300 s"
        time.sleep(0.02)
    os.killpg(run.pid, signal.SIGKILL)
    run.wait()
    return _units(out, pattern)


def _comparable(value, out: Path):
    """``value`` without timing fields, with ``out`` replaced by a placeholder."""
    if isinstance(value, dict):
        return {k: _comparable(v, out) for k, v in value.items() if k not in TIMING}
    if isinstance(value, list):
        return [_comparable(v, out) for v in value]
    if isinstance(value, str):
        return value.replace(str(out.resolve()), "OUT").replace(str(out), "OUT")
    return value


#: The command the default tier kills: training (the benchmark's resume is the default tier's
#: tests/cli/test_benchmark_cli.py); the rest in `make test-slow`.
DEFAULT_TIER = ("train",)


@pytest.mark.parametrize(
    "name", [n if n in DEFAULT_TIER else pytest.param(n, marks=pytest.mark.slow) for n in COMMANDS]
)
def test_a_killed_command_resumes_to_the_uninterrupted_result(name, tmp_path):
    reference = _finish(_argv(name, tmp_path / "reference", tmp_path))
    out = tmp_path / "killed"
    argv, (_, pattern) = _argv(name, out, tmp_path), COMMANDS[name]
    stamps = _kill_after_first_unit(argv, pattern, out)
    for path in out.rglob("*.json"):  # whatever the kill left is whole
        json.loads(path.read_text())
    for store in out.rglob("*.sqlite"):
        read_rows(store)
    resumed = _finish(argv)
    now = _units(out, pattern)
    assert {unit: now.get(unit) for unit in stamps} == stamps  # nothing recomputed
    assert not list(out.rglob(".*.tmp"))
    if name == "train":  # a resumed run ends where an uninterrupted one does
        assert resumed["timesteps"] == reference["timesteps"] == 640
        assert resumed["resumed_from"] > 0
        return
    if name == "finetune":  # the same run (weights, evaluations), resumed from an update
        assert resumed.pop("resumed_from") > 0 == reference.pop("resumed_from")
    assert _comparable(resumed, out) == _comparable(reference, tmp_path / "reference")


def test_the_workers_of_a_run_killed_alone_exit(tmp_path):
    """``kill PID`` of a run (not of its process group) leaves no worker holding its memory:
    a forkserver worker is not the run's child, so it watches the run's pid."""
    from stsf_gym.experiments.jobs.backends import PARENT_CHECK_S

    pid_files = [tmp_path / f"worker-{i}.pid" for i in range(2)]
    jobs = [{"pid_file": str(path), "seconds": 600} for path in pid_files]
    script = (
        "import sys; sys.path.insert(0, 'tests')\n"
        "from stsf_gym.experiments.jobs.backends import process_runner\n"
        "from worker_jobs import note_pid_and_wait\n"
        f"list(process_runner(2)(note_pid_and_wait, {jobs!r}))\n"
    )
    run = subprocess.Popen([sys.executable, "-c", script], cwd=ROOT)
    deadline = time.monotonic() + 120
    while not all(path.exists() and path.read_text() for path in pid_files):
        assert run.poll() is None and time.monotonic() < deadline, "the workers did not start"
        time.sleep(0.05)
    workers = [int(path.read_text()) for path in pid_files]
    run.kill()  # the run alone, as `kill -9 PID` does
    run.wait()
    deadline = time.monotonic() + 5 * PARENT_CHECK_S
    while alive := [pid for pid in workers if _running(pid)]:
        assert time.monotonic() < deadline, f"workers {alive} outlived their run"
        time.sleep(0.1)


def _running(pid: int) -> bool:
    """Whether ``pid`` is a process that has not exited (a zombie has)."""
    try:
        status = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return status != "Z"
