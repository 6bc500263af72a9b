"""``stsf-gym replay``: pose sources rerun on recorded MCAP logs, scored like an evaluation.

Each log (:mod:`stsf_gym.recording`, or a log of your own robot: docs/log_format.md) is read
once and every pose source runs over its observations, with no simulator. Writes
``results.json`` (results schema, one row per pose source over the logs), ``results.md`` and
each run's TUM trajectories (``trajectories/<log>-<source>/{truth,estimate}.txt``; a log
without ``/ground_truth/pose`` at every step gets its estimates only, and no row). Success
and collision are the recorded run's (its agent drove on the recorded estimate). A row is
``approximate`` when a log's camera frames were stored lossy (JPEG): the replay then differs
from what ran live. ``recorded_difference`` is the largest position difference (m) from the
log's own estimate of that pose source, where it holds one (0 on a lossless recording).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from tqdm import tqdm

from stsf_gym.experiments.episodes import EpisodeResult
from stsf_gym.experiments.reports import write_report
from stsf_gym.experiments.result_tables import results_tables
from stsf_gym.experiments.statistics import summarise
from stsf_gym.metrics import distance_to_path
from stsf_gym.recording.log_reader import RecordedLog, read_log
from stsf_gym.recording.replay import ReplayedRun, check_replayable, pose_source, replay
from stsf_gym.results import SCHEMA_VERSION, stat
from stsf_gym.tum import write_tum
from stsf_gym.wrappers import COV_LIMIT

AGENT = "recorded"  # the agent column: whatever drove when the log was recorded


def replay_logs(logs: list[str | Path], estimators: list[str], out: str | Path) -> dict:
    """Run ``estimators`` over every log; write the report to ``out``; return the summary."""
    out = Path(out)
    read = [read_log(path) for path in logs]  # a bad log fails before any work
    for log in read:  # ... and so does a log that lacks what a pose source reads
        for name in estimators:
            check_replayable(log, name, pose_source(name))
    episodes: dict[str, list[EpisodeResult]] = {name: [] for name in estimators}
    differences: dict[str, list[float]] = {name: [] for name in estimators}
    walls: dict[str, list[float]] = {name: [] for name in estimators}
    for log in tqdm(read, desc="replay", unit="log"):
        observations = list(log.observations())
        for name in estimators:
            run = replay(log, name, observations)
            walls[name].append(run.wall_s)
            target = out / "trajectories" / f"{log.path.stem}-{name}"
            write_tum(target / "estimate.txt", log.times, run.means)
            if log.truth is None:  # nothing to score it against
                continue
            episodes[name].append(episode_result(log, run))
            write_tum(target / "truth.txt", log.times, log.truth)
            if name in log.estimates:
                recorded = log.estimates[name][0]
                differences[name].append(float(np.abs(recorded[:, :2] - run.means[:, :2]).max()))
    rows = []
    for name, runs in episodes.items():
        if not runs:
            continue
        row = summarise(name, runs, AGENT)
        row["approximate"] = any(not log.lossless for log in read)
        row["recorded_difference_m"] = max(differences[name]) if differences[name] else None
        row["replay_wall_s"] = stat(walls[name])
        rows.append(row)
    summary = {
        "schema_version": SCHEMA_VERSION,
        "logs": [str(log.path) for log in read],
        "unscored": [str(log.path) for log in read if log.truth is None],
        "rows": rows,
    }
    table = results_tables(rows) if rows else "No log has a truth.\n"
    config = {str(log.path): log.episode for log in read}
    seeds = [log.episode.get("seed") or 0 for log in read]
    write_report(out, summary, f"Replay of {len(read)} log(s)", table, config=config, seeds=seeds)
    return summary


def episode_result(log: RecordedLog, run: ReplayedRun) -> EpisodeResult:
    """The replayed run as an evaluation's episode: the estimate as the wrapper hands it to the
    agent (yaw wrapped, float32), the log's truth, the recorded ending."""
    truth = np.asarray(log.truth, float)
    step = np.hypot(*np.diff(truth[:, :2], axis=0).T)
    travelled = np.concatenate([[0.0], np.cumsum(step)])
    wrapped = np.arctan2(np.sin(run.means[:, 2]), np.cos(run.means[:, 2]))
    estimates = np.column_stack([run.means[:, :2], wrapped]).astype(np.float32).astype(float)
    covs = np.clip(run.covs, -COV_LIMIT, COV_LIMIT).astype(np.float32).astype(float)
    rows, cols = np.triu_indices(3)
    path = log.episode.get("path")
    steps = len(truth) - 1
    return EpisodeResult(
        spec={
            "world": log.episode.get("world", "log"),
            "estimator": run.name,
            "seed": log.episode.get("seed") or 0,
            "agent": AGENT,
            "log": str(log.path),
        },
        outcome=log.end.get("outcome", "unknown"),
        distance=float(travelled[-1]),
        sim_time=float(log.times[-1]),
        steps=steps,
        times=log.times.tolist(),
        travelled=travelled.tolist(),
        true_poses=truth.tolist(),
        estimates=estimates.tolist(),
        covariances=covs[:, rows, cols].tolist(),
        nis=[list(v) for v in run.nis],
        path_errors=distance_to_path(truth[:, :2], path).tolist() if path else [],
        frames=run.counters.get("frames", 0),
        camera_frames=0,  # whether a landmark was in view needs the simulator: not scored
        frames_in_view=0,
        frames_matched=run.counters.get("frames_matched", 0),
        landmark_updates=run.counters.get("landmark_updates", 0),
        gated_out=run.counters.get("gated_out", 0),
        relocalised=run.counters.get("relocalised", 0),
        finite=bool(np.isfinite(run.means).all() and np.isfinite(run.covs).all()),
        min_cov_eigenvalue=float(np.linalg.eigvalsh(run.covs).min()),
        stage_ms_per_step={k: 1000 * v / max(steps, 1) for k, v in run.timings.items()},
    )
