"""The pose sources a wrapper accepts, how one is driven, and the check of what it returns:
the estimators, the privileged true pose (:class:`TruePose`) and ``degraded-truth``, each
checked against the env's sensors; every estimate three finite numbers and a symmetric
positive definite 3x3 covariance before an agent sees it (:func:`check_estimate`)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from stsf_gym.estimators import (
    ESTIMATORS,
    PRIVILEGED,
    PoseEstimator,
    SensorModel,
    estimator_class,
)
from stsf_gym.validation import ConfigError
from stsf_gym.wrappers.state_history import EstimatorDriver, history_horizon

#: The privileged pose source: the true pose from ``info``, for reference runs only.
TRUTH = "truth"
#: Standard deviations (m, m, rad) reported with the true pose: tiny, fixed.
TRUTH_STD = (0.001, 0.001, 0.001)
#: Every pose source a wrapper accepts: the estimators, the privileged ``truth`` and the
#: privileged ``degraded-truth`` (the accuracy curve's dial).
POSE_SOURCES = (*ESTIMATORS, TRUTH, *PRIVILEGED)


def check_pose_source(name: str) -> None:
    """Fail (:class:`ConfigError`) unless ``name`` is a pose source: one of
    :data:`POSE_SOURCES`, a registered estimator or a ``package.module:Class`` estimator."""
    if name != TRUTH:
        estimator_class(name)


def check_sensors(name: str, sensors: tuple[str, ...], camera_enabled: bool) -> None:
    """Refuse pose source ``name`` (reading ``sensors``) on an env whose camera is off."""
    if "camera" in sensors and not camera_enabled:
        raise ConfigError(
            f"pose source {name!r} reads the camera, but camera.enabled is false; switch it on "
            "(camera.mode: fast simulates detections without rendering)",
            "camera.enabled",
        )


def estimator_driver(
    estimator: PoseEstimator, delay_s: float, jitter_s: float, control_dt: float
) -> EstimatorDriver:
    """The driver of ``estimator``: through a history of late frames when the camera has a
    latency (``delay_s``, ``jitter_s``), unless the source is privileged."""
    horizon = None if estimator.privileged else history_horizon(delay_s, jitter_s, control_dt)
    return EstimatorDriver(estimator, horizon)


class TruePose(PoseEstimator):
    """The privileged reference "estimator": the true pose with a tiny fixed covariance.

    Not an estimator: the wrapper hands it ``info["true_pose"]`` (:meth:`see`), the one place
    where ``info`` feeds a pose. It gives agents trained or run on perfect localization, to
    compare the real estimators against.
    """

    name = TRUTH
    sensors = ()
    privileged = True

    def reset(self, model: SensorModel, initial_pose, initial_cov) -> None:
        """Start at the true pose with the fixed :data:`TRUTH_STD` covariance."""
        super().reset(model, initial_pose, np.diag(np.square(TRUTH_STD)))

    def see(self, true_pose: np.ndarray) -> None:
        """Take the true pose of the step (from ``info``)."""
        self.mean = np.asarray(true_pose, dtype=float).copy()

    def update(self, obs: dict, dt: float) -> tuple[np.ndarray, np.ndarray]:
        return self.mean, self.cov


class EstimateError(ValueError):
    """A pose source returned what no pose estimate can be: a pose that is not three finite
    numbers, or a covariance that is not a symmetric positive definite 3x3 matrix."""


#: How far a covariance may be from symmetric, relative to its largest entry (rounding).
SYMMETRY_TOLERANCE = 1e-6


def check_estimate(name: str, mean: Any, cov: Any) -> tuple[np.ndarray, np.ndarray]:
    """``mean`` and ``cov`` as float arrays if they are a pose estimate, else an
    :class:`EstimateError` naming pose source ``name`` (checked at every step it returns, on
    plain floats: a 3x3 check costs more in numpy's call overhead than in arithmetic)."""
    mean, cov = np.asarray(mean, dtype=float), np.asarray(cov, dtype=float)
    where = f"pose source {name!r} returned"
    if mean.shape != (3,) or not all(map(math.isfinite, mean.tolist())):
        raise EstimateError(f"{where} the pose {mean.tolist()}: not three finite numbers x, y, yaw")
    entries = cov.ravel().tolist()
    if cov.shape != (3, 3) or not all(map(math.isfinite, entries)):
        raise EstimateError(f"{where} the covariance {cov.tolist()}: not a finite 3x3 matrix")
    scale = max(map(abs, entries))
    asymmetry = max(abs(entries[i] - entries[j]) for i, j in ((1, 3), (2, 6), (5, 7)))
    if asymmetry > SYMMETRY_TOLERANCE * scale:
        raise EstimateError(f"{where} the covariance {cov.tolist()}: not symmetric")
    if not _cholesky_succeeds(entries):
        eigenvalues = np.linalg.eigvalsh(cov).tolist()
        raise EstimateError(
            f"{where} the covariance {cov.tolist()}: not positive definite (eigenvalues "
            f"{eigenvalues}); NEES and the agent's uncertainty need a positive definite one"
        )
    return mean, cov


def _cholesky_succeeds(c: list[float]) -> bool:
    """Whether the Cholesky factorization ``L L^T`` of the symmetric 3x3 matrix ``c`` (row
    major; its lower triangle read, as ``np.linalg.cholesky`` does) exists: every pivot > 0."""
    if not c[0] > 0:
        return False
    l00 = math.sqrt(c[0])
    l10, l20 = c[3] / l00, c[6] / l00
    pivot = c[4] - l10 * l10
    if not pivot > 0:
        return False
    l21 = (c[7] - l20 * l10) / math.sqrt(pivot)
    return c[8] - l20 * l20 - l21 * l21 > 0
