"""What a recorder is handed: the episode's start (:class:`EpisodeStart`) and each step
(:class:`StepRecord`), and the :class:`Recorder` interface of the MCAP and Rerun writers."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from stsf_gym.estimators import SensorModel
from stsf_gym.vision.detector import Detection
from stsf_gym.vision.predicted import BoardPrediction


@dataclass(frozen=True)
class RobotLayout:
    """Where the robot's sensors are, for drawing and TF (not needed by an estimator)."""

    body_radius: float
    sonar_axes: np.ndarray  # transducer headings (rad, robot frame)
    sonar_height: float
    sonar_fov: float  # full beam width (rad)
    sonar_limits: tuple[float, float]  # min, max range (m)
    wall_height: float
    max_speed: float  # m/s at action 1
    max_yaw_rate: float  # rad/s at action 1


@dataclass(frozen=True)
class EpisodeStart:
    """The episode as an estimator starts it: the sensor model, the start pose and its
    covariance, the control period, and labels (``meta``: world, seed, pose source, ...)."""

    model: SensorModel
    initial_pose: np.ndarray
    initial_cov: np.ndarray
    control_dt: float
    layout: RobotLayout
    meta: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class FrameDetections:
    """A frame's detections as the estimator's detector saw them (image pixels), the ones only
    the track-aided search found, and the boards it predicted."""

    found: list[Detection]
    aided: list[Detection]
    predictions: list[BoardPrediction]


@dataclass(frozen=True)
class StepRecord:
    """One control step (or the reset, ``action`` None): the env's observation, the truth,
    and each pose source's estimate ``name -> (mean, cov)``."""

    time: float
    obs: dict
    true_pose: np.ndarray
    camera_pose: np.ndarray  # true world-from-camera 4x4 of the frame in obs
    action: np.ndarray | None
    estimates: dict[str, tuple[np.ndarray, np.ndarray]]
    detections: FrameDetections | None = None
    counters: dict[str, int] = field(default_factory=dict)  # the estimator's, so far


class Recorder(Protocol):
    """Writes one episode: :meth:`start`, :meth:`step` per record, :meth:`close`."""

    path: Any

    def start(self, start: EpisodeStart) -> None:
        """Begin the file with the episode's start (layout, sensor model, metadata)."""

    def step(self, record: StepRecord) -> None:
        """Write one control step."""

    def close(self, end: dict | None = None) -> None:
        """Finish the file; ``end`` is the episode's ending (``outcome``), when it ended."""


def nanoseconds(seconds: float) -> int:
    """A timestamp of simulated time, in integer nanoseconds."""
    return round(seconds * 1e9)
