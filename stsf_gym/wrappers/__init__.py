"""The wrappers between the simulator and an agent, one job each.

- :class:`PoseEstimateWrapper` (:mod:`~stsf_gym.wrappers.estimate`) adds ``obs["pose"]`` and
  ``obs["pose_cov"]``: the estimate of a pose source, checked
  (:mod:`~stsf_gym.wrappers.pose_sources`), from the robot's model of its sensors
  (:func:`sensor_model`, the one seam between the simulator and the estimators).
- :class:`CameraPointingWrapper` (:mod:`~stsf_gym.wrappers.pointing`), over it, points the pan
  camera from that estimate, sweeps it while an unknown start is searched for, and takes the
  pan entry out of the agent's action.

:func:`stsf_gym.episode_env.make_episode_env` builds the standard stack, both of them over a
pan camera. Each wrapper that has something to show asks the env's map view to draw it
(``env.unwrapped.draw_on_map``); the view asks at every frame, in the render path.
"""

from stsf_gym.wrappers.estimate import COV_LIMIT, START_STD, PoseEstimateWrapper
from stsf_gym.wrappers.pointing import FOUND_STD, SWEEP_PERIOD_S, CameraPointingWrapper
from stsf_gym.wrappers.pose_sources import (
    POSE_SOURCES,
    SYMMETRY_TOLERANCE,
    TRUTH,
    TRUTH_STD,
    EstimateError,
    TruePose,
    check_estimate,
    check_pose_source,
    check_sensors,
    estimator_driver,
)
from stsf_gym.wrappers.sensor_model import robot_map, sensor_model

__all__ = [
    "COV_LIMIT",
    "FOUND_STD",
    "POSE_SOURCES",
    "START_STD",
    "SWEEP_PERIOD_S",
    "SYMMETRY_TOLERANCE",
    "TRUTH",
    "TRUTH_STD",
    "CameraPointingWrapper",
    "EstimateError",
    "PoseEstimateWrapper",
    "TruePose",
    "check_estimate",
    "check_pose_source",
    "check_sensors",
    "estimator_driver",
    "robot_map",
    "sensor_model",
]
