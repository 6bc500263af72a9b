"""The pose sources a wrapper accepts, and how one is driven: the estimators, the privileged
true pose (:class:`TruePose`) and ``degraded-truth``, each checked against the env's sensors."""

from __future__ import annotations

import numpy as np

from stsf_gym.estimators import (
    ESTIMATORS,
    PRIVILEGED,
    PoseEstimator,
    SensorModel,
    estimator_class,
)
from stsf_gym.state_history import EstimatorDriver, history_horizon
from stsf_gym.validation import ConfigError

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
    name: str, estimator: PoseEstimator, delay_s: float, jitter_s: float, control_dt: float
) -> EstimatorDriver:
    """The driver of pose source ``name``: through a history of late frames when the camera
    has a latency (``delay_s``, ``jitter_s``), unless the source is privileged."""
    privileged = name in (TRUTH, *PRIVILEGED)
    horizon = None if privileged else history_horizon(delay_s, jitter_s, control_dt)
    return EstimatorDriver(estimator, horizon)


class TruePose(PoseEstimator):
    """The privileged reference "estimator": the true pose with a tiny fixed covariance.

    Not an estimator: the wrapper hands it ``info["true_pose"]`` (:meth:`see`), the one place
    where ``info`` feeds a pose. It gives agents trained or run on perfect localization, to
    compare the real estimators against.
    """

    name = TRUTH
    sensors = ()

    def reset(self, model: SensorModel, initial_pose, initial_cov) -> None:
        """Start at the true pose with the fixed :data:`TRUTH_STD` covariance."""
        super().reset(model, initial_pose, np.diag(np.square(TRUTH_STD)))

    def see(self, true_pose: np.ndarray) -> None:
        """Take the true pose of the step (from ``info``)."""
        self.mean = np.asarray(true_pose, dtype=float).copy()

    def update(self, obs: dict, dt: float) -> tuple[np.ndarray, np.ndarray]:
        return self.mean, self.cov
