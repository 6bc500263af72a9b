"""Any pose source rerun on a recorded log, with no simulator: what the live wrapper did.

:class:`~stsf_gym.wrappers.PoseEstimateWrapper` resets the estimator at the start pose and
drives it with each step's observation (:class:`~stsf_gym.wrappers.state_history.EstimatorDriver`:
with a camera latency, late frames are fused at their exposure); :func:`replay` runs the same
driver, with the recorded latency, on the observations of a
:class:`~stsf_gym.recording.log_reader.RecordedLog` and the control period. On a log with
lossless frames the estimates equal the live run's bit for bit. The privileged sources
(``truth``, ``degraded-truth``) are handed the log's true poses as the wrapper hands them
``info["true_pose"]``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from stsf_gym.estimators import PoseEstimator, make_estimator
from stsf_gym.recording import topics
from stsf_gym.recording.log_reader import RecordedLog
from stsf_gym.validation import ConfigError
from stsf_gym.wrappers import TRUTH, TruePose, check_estimate, estimator_driver


@dataclass
class ReplayedRun:
    """One pose source over a log: its estimate and covariance at every step (the start's
    first), its counters, innovations and wall time per stage, and the replay's wall time."""

    name: str
    means: np.ndarray  # (N, 3), float64 as the estimator returned them
    covs: np.ndarray  # (N, 3, 3)
    counters: dict[str, int]
    nis: list[tuple[float, int]]
    timings: dict[str, float]
    wall_s: float


def pose_source(name: str, **options) -> PoseEstimator:
    """The pose source ``name`` as the wrapper makes it."""
    return TruePose() if name == TRUTH else make_estimator(name, **options)


def check_replayable(log: RecordedLog, name: str, estimator: PoseEstimator) -> None:
    """Refuse (:class:`ConfigError`) to run pose source ``name`` on ``log`` unless the log
    holds every topic it needs: its sensors' (:data:`topics.SENSOR_TOPICS`), and the true
    poses for a privileged source."""
    if estimator.privileged and log.truth is None:
        raise ConfigError(f"{log.path}: {name} needs the true poses, and the log has none")
    for sensor in estimator.sensors:
        for group in topics.SENSOR_TOPICS.get(sensor, ()):
            if not log.topics & set(group):
                raise ConfigError(
                    f"{log.path}: pose source {name!r} reads the {sensor}, and the log has no "
                    f"{' or '.join(group)} topic (see docs/log_format.md)"
                )


def replay(log: RecordedLog, name: str, observations: list[dict] | None = None, **options):
    """Run pose source ``name`` (``options`` over its YAML settings) over ``log``; pass
    ``observations`` (``list(log.observations())``) to decode the frames once for many."""
    estimator = pose_source(name, **options)
    check_replayable(log, name, estimator)
    latency = log.camera_latency
    driver = estimator_driver(estimator, latency.delay_s, latency.jitter_s, log.control_dt)
    truth = log.truth if log.truth is not None else [None] * len(log.stamps)
    started = time.perf_counter()
    steps = iter(observations if observations is not None else log.observations())
    estimator.seed(log.episode.get("seed"))
    estimator.reset(log.model, log.initial_pose, log.initial_cov)
    driver.start(next(steps), truth[0])  # the start: the estimator is reset, not updated
    means, covs = [estimator.mean.copy()], [estimator.cov.copy()]
    for k, obs in enumerate(steps, start=1):
        mean, cov = check_estimate(name, *driver.update(obs, log.control_dt, truth[k]))
        means.append(mean.copy())
        covs.append(cov.copy())
    estimator = driver.estimator  # the live one (a rewound copy after a late frame)
    return ReplayedRun(
        name=name,
        means=np.array(means),
        covs=np.array(covs),
        counters=dict(estimator.counters),
        nis=[tuple(v) for v in estimator.innovations()],
        timings=dict(estimator.timings),
        wall_s=time.perf_counter() - started,
    )
