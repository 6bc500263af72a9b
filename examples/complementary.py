"""Your own estimator in the comparison: a complementary filter, no YAML and no package edit.

Every step the wheel odometry predicts the pose (the package's dead reckoning, covariance and
all); every map board the camera sees gives the robot's full pose on its own (the board's PnP
pose through its map pose, ``map (+) (-) z``), and the filter moves a fixed fraction ``gain``
of the way towards it::

    x <- x (+) gain * (x_board - x)          (heading difference wrapped)
    P <- (1 - gain)^2 P + gain^2 C_board     (the two taken as independent)

Run it beside the package's estimators from the repository root::

    stsf-gym evaluate --estimators odometry,examples.complementary:ComplementaryFilter \\
        --seeds 2 --set camera.mode=fast

or in Python: ``PoseEstimateWrapper(env, "examples.complementary:ComplementaryFilter",
gain=0.3)``. Its settings are :class:`ComplementarySettings`' defaults with keyword options
over them, checked like the package's own (``gain`` must lie in (0, 1]).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, ClassVar

import numpy as np

from stsf_gym.estimators.frame_detector import FrameDetector
from stsf_gym.estimators.landmark_observation import observe, robot_pose_from_landmark
from stsf_gym.estimators.odometry_estimator import OdometryEstimator
from stsf_gym.geometry import wrap_angle
from stsf_gym.validation import Range


@dataclass(frozen=True)
class ComplementarySettings:
    gain: Annotated[float, Range(gt=0, le=1)] = 0.2  # fraction moved towards a board's pose
    sigma_px: Annotated[float, Range(gt=0)] = 0.15  # px, square-centre noise of the PnP pose
    mount_std: Annotated[float, Range(ge=0)] = 0.003  # m, camera mount error (dead reckoning's)


class ComplementaryFilter(OdometryEstimator):
    """Odometry, pulled towards the pose each seen board gives by a fixed ``gain``."""

    name = "complementary"
    settings_type: ClassVar[type] = ComplementarySettings

    def reset(self, model, initial_pose, initial_cov) -> None:
        super().reset(model, initial_pose, initial_cov)
        self.detector = FrameDetector(model.pattern, set(model.landmarks), model.camera_calibration)

    def update(self, obs: dict, dt: float) -> tuple[np.ndarray, np.ndarray]:
        self.predict(obs)
        if int(obs["image_new"]):
            pan, tilt = (float(a) for a in obs["camera_pan_tilt"])
            detections = self.detector(obs)
            self.counters["frames"] += 1  # counters give the evaluation's match rate
            self.counters["frames_matched"] += bool(detections)
            for detection in detections:
                seen = observe(detection, self.model, pan, tilt, self.settings.sigma_px)
                if seen is not None:
                    self.blend(*robot_pose_from_landmark(seen.landmark, seen.z, seen.cov))
        return self.mean, self.cov

    def blend(self, pose: np.ndarray, cov: np.ndarray) -> None:
        gain = self.settings.gain
        offset = pose - self.mean
        offset[2] = wrap_angle(offset[2])
        self.mean = self.mean + gain * offset
        self.mean[2] = wrap_angle(self.mean[2])
        self.restart(self.mean, (1 - gain) ** 2 * self.cov + gain**2 * cov)
        self.counters["landmark_updates"] += 1
