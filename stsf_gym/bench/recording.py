"""What recording costs, and how fast a replay is: the follower drives the whole IRL corridor
(about 24 m) on STSF in the fast and the rendered sensor mode, once unrecorded and once per
recording format, in one process pinned to one core.

The overhead is the CPU time spent in the recorder (:attr:`RecordEpisode.cpu_s`: building the
messages, encoding frames, writing) over the unrecorded episode's CPU time; CPU time, because
on a shared machine wall time measures the neighbours. Beside it: the recorder's wall time, and
what the recorded episode's process CPU time (all threads: the Rerun SDK encodes and writes in
its own) exceeds the unrecorded one's, which is noisier (two runs differ by a few per cent).
The process is warm: the writers' libraries are imported before any episode (their import, paid
once per process by its first recording, is reported as ``import_cpu_s``).
The replay reads each mode's lossless (raw) MCAP and reruns STSF on it (decoding every frame,
running the detector) with no simulator; its speed-up is the live episode's CPU time over the
replay's, reading included. The process reports the package modules it loaded, for the bench's
provenance.
"""

from __future__ import annotations

import importlib
import os
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

from stsf_gym.results.code_identity import run_reporting_modules, worker_result

#: (format, frames) recorded per sensor mode; the fast mode has no frames to store.
RECORDINGS = {
    "fast": [("mcap", "raw"), ("rerun", "-")],
    "rendered": [("mcap", "raw"), ("mcap", "jpeg"), ("mcap", "png"), ("rerun", "-")],
}
ESTIMATOR, WORLD = "stsf", "irl_corridor"


def recording_costs(seed: int = 0, cpu: int | None = 0) -> dict:
    """Measure every recording case in a fresh process (pinned to ``cpu`` when given)."""
    with ProcessPoolExecutor(1, mp_context=get_context("spawn")) as pool:
        return worker_result(pool.submit(run_reporting_modules, _measure, seed, cpu).result())


def _episode(mode: str, seed: int, record: tuple[str, str] | None, folder: Path) -> dict:
    from stsf_gym.agents.registry import make_agent
    from stsf_gym.episode_env import make_episode_env
    from stsf_gym.recording.wrapper import RecordEpisode

    env = make_episode_env(WORLD, ESTIMATOR, {"camera": {"mode": mode}})
    if record is not None:
        env = RecordEpisode(env, folder, record[0], record[1], f"{mode}-{record[0]}-{record[1]}")
    start, cpu, done = time.perf_counter(), time.process_time(), False
    obs, info = env.reset(seed=seed)
    follower = make_agent("follower")
    follower.begin(env)
    act = follower.act
    while not done:
        obs, _, terminated, truncated, info = env.step(act(obs))
        done = terminated or truncated
    env.close()
    row = {
        "wall_s": time.perf_counter() - start,
        "cpu_s": time.process_time() - cpu,
        "distance_m": float(info["distance_travelled"]),
    }
    if record is not None:
        (path,) = env.paths
        row.update(
            recorder_cpu_s=env.cpu_s,
            recorder_wall_s=env.wall_s,
            path=path,
            size_mb=path.stat().st_size / 1e6,
        )
    return row


def _measure(seed: int, cpu: int | None) -> dict:
    if cpu is not None and hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {cpu % os.cpu_count()})
    imports = {}
    for name in ("mcap_writer", "rerun_writer"):
        cpu = time.process_time()
        importlib.import_module(f"stsf_gym.recording.{name}")
        imports[name] = time.process_time() - cpu
    from stsf_gym.recording.log_reader import read_log
    from stsf_gym.recording.replay import replay

    rows, replays = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for mode, recordings in RECORDINGS.items():
            live = _episode(mode, seed, None, Path(tmp))
            for fmt, frames in recordings:
                recorded = _episode(mode, seed, (fmt, frames), Path(tmp))
                rows.append(
                    {
                        "mode": mode,
                        "format": fmt,
                        "frames": frames if mode == "rendered" else "-",
                        "distance_m": recorded["distance_m"],
                        "episode_cpu_s": live["cpu_s"],
                        "recorder_cpu_s": recorded["recorder_cpu_s"],
                        "overhead": recorded["recorder_cpu_s"] / live["cpu_s"],
                        "recorder_wall_s": recorded["recorder_wall_s"],
                        "process_cpu_increase": recorded["cpu_s"] / live["cpu_s"] - 1,
                        "size_mb": recorded["size_mb"],
                    }
                )
                if fmt == "mcap" and frames == "raw":
                    start, cpu = time.perf_counter(), time.process_time()
                    run = replay(read_log(recorded["path"]), ESTIMATOR)
                    total = time.process_time() - cpu
                    replays.append(
                        {
                            "mode": mode,
                            "episode_cpu_s": live["cpu_s"],
                            "replay_cpu_s": total,
                            "replay_wall_s": time.perf_counter() - start,
                            "estimator_wall_s": run.wall_s,
                            "speed_up": live["cpu_s"] / total,
                        }
                    )
    return {"recordings": rows, "replays": replays, "import_cpu_s": imports}
