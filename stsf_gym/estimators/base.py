"""What every pose estimator shares: the robot's sensor model and one interface.

An estimator never reads ``info``: what it knows comes from the observation and from a
:class:`SensorModel`, the robot's own (believed) description of its sensors and the landmark
map, rebuilt at each reset because the believed odometry calibration changes per episode.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from stsf_gym.camera_model import CameraCalibration
from stsf_gym.estimators.odometry_model import OdometryNoise
from stsf_gym.estimators.settings import OdometrySettings
from stsf_gym.fusion.chi_square import chi_square_quantile
from stsf_gym.geometry import OdometryCalibration
from stsf_gym.validation import ConfigError
from stsf_gym.vision.landmarks import LandmarkPattern

if TYPE_CHECKING:
    from stsf_gym.estimators.frame_detector import FrameDetector


@dataclass(frozen=True)
class MapLandmark:
    """A landmark of the map: id, board centre and outward normal, square centres (world)."""

    id: int
    centre: np.ndarray
    normal: np.ndarray
    square_centres: np.ndarray


@dataclass(frozen=True)
class SonarRingModel:
    """The sonar ring as the robot knows it: transducer headings (rad, robot frame), the ring's
    radius (m), the readable range (m) and the range noise ``std + std_per_m * range``."""

    axes: np.ndarray
    ring_radius: float
    min_range: float
    max_range: float
    noise_std: float
    noise_std_per_m: float


@dataclass(frozen=True)
class SensorModel:
    """The robot's knowledge: odometry calibration and noise, camera, mount, landmark map.

    ``camera_calibration`` is the camera as the robot believes it is (K and distortion, with
    this episode's calibration error); detections are undistorted with it, so the estimators
    use ``camera_matrix`` (its K) as an ideal pinhole camera. ``camera_calibration_std`` is
    how far the robot knows that calibration may be off: its principal point as a heading
    (std of the horizontal principal point error over the focal length, rad) and its focal
    length (relative std); every estimator with a camera considers both. Built from an env by
    :func:`stsf_gym.wrappers.sensor_model` (the one place that reads an env), or from logged
    data by hand."""

    calibration: OdometryCalibration
    odometry_noise: OdometryNoise
    camera_calibration: CameraCalibration
    camera_calibration_std: tuple[float, float]  # rad, relative: see below
    camera_matrix: np.ndarray
    image_size: tuple[int, int]  # width, height
    robot_from_camera: Callable[[float, float], np.ndarray]  # e.g. a PanTiltMount
    landmarks: dict[int, MapLandmark]
    pattern: LandmarkPattern
    walls: np.ndarray  # (K, 4) wall centre-line segments x1, y1, x2, y2 of the map
    wall_thickness: float = 0.0  # m: a wall's faces lie half of it off its centre line
    sonar: SonarRingModel | None = None  # None: no sonar (the map's walls unused)
    body_radius: float = 0.0  # m, the robot's footprint: the free space keeps it off walls


def chi_square_gate(probability: float, dof: int) -> float:
    """The squared Mahalanobis distance that keeps ``probability`` of consistent measurements."""
    if not 0 < probability < 1:
        raise ValueError(f"gate_probability must be in (0, 1), got {probability}")
    return chi_square_quantile(probability, dof)


class PoseEstimator(ABC):
    """``reset(model, initial_pose, initial_cov)`` then ``update(obs, dt) -> (mean, cov)``.

    ``mean`` is ``[x, y, yaw]`` in the world frame, ``cov`` its 3x3 covariance.
    :attr:`timings` sums the wall time of each stage; :attr:`counters` counts events
    (frames, landmark matches, rejected measurements).

    The abilities some pose sources have are declared here with the plain estimator's answer,
    so the wrappers and a log's replay call them on any source: :attr:`privileged` (handed the
    true pose, :meth:`see`), :meth:`seed` (its own random draws), :meth:`spread_prior` and
    :attr:`confirmed` (global localization), :meth:`believed_odometry` (the noise its sensor
    model takes) and :attr:`detector` (the camera frames' detections, for recordings).
    """

    name: str = ""
    #: The sensors the estimator reads: a pose source whose sensor is switched off in the env
    #: is refused (:func:`stsf_gym.wrappers.check_sensors`), never run as something else.
    sensors: tuple[str, ...] = ("encoders",)
    #: A privileged source: handed ``info["true_pose"]`` at every step (:meth:`see`), for
    #: reference runs only; never delayed by a camera latency's history.
    privileged: ClassVar[bool] = False

    def __init__(self) -> None:
        self.timings: dict[str, float] = defaultdict(float)
        self.counters: dict[str, int] = defaultdict(int)
        self.model: SensorModel | None = None
        self.mean, self.cov = np.zeros(3), np.eye(3)
        #: Whether a board agreed with the estimate since it last forgot its start
        #: (:meth:`spread_prior`); a camera pointed from an unconfirmed estimate sweeps on.
        self.confirmed = True
        #: The detector of the camera frames, for an estimator that reads them (recordings
        #: log its detections).
        self.detector: FrameDetector | None = None

    def seed(self, seed: int | None) -> None:
        """Seed the estimator's own random draws for the episode ``reset(seed=...)`` starts
        (``None``: keep the stream); a source that draws none ignores it."""
        return None

    def see(self, true_pose: np.ndarray) -> None:
        """Take the step's true pose: only a :attr:`privileged` source is handed it."""
        raise TypeError(f"{type(self).__name__} is not privileged: it is never shown the truth")

    def spread_prior(self) -> None:
        """Forget the start (an unknown start): only an estimator that localizes globally can."""
        raise ConfigError(
            f"reset option unknown_start needs an estimator that localizes globally "
            f"(mcl), not {self.name or type(self).__name__!r}"
        )

    def believed_odometry(self) -> OdometrySettings | None:
        """The odometry noise the estimator believes, for its sensor model
        (:func:`stsf_gym.wrappers.sensor_model`); None: the odometry estimator's defaults."""
        return None

    def reset(self, model: SensorModel, initial_pose, initial_cov) -> None:
        """Start an episode on the robot ``model`` at ``initial_pose`` ``[x, y, yaw]`` with
        covariance ``initial_cov`` (3x3); clears the timings and counters.
        """
        self.model = model
        self.mean = np.asarray(initial_pose, dtype=float).copy()
        self.cov = np.asarray(initial_cov, dtype=float).copy()
        self.timings.clear()
        self.counters.clear()

    @abstractmethod
    def update(self, obs: dict, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Fold in one step's observation; return the pose estimate and its covariance."""

    def innovations(self) -> list[tuple[float, int]]:
        """NIS and dimension of every measurement innovation tested this episode."""
        return []

    def timed(self, stage: str):
        """Context manager adding the wall time of a block to ``timings[stage]``."""
        return _Timer(self.timings, stage)


class _Timer:
    def __init__(self, timings: dict[str, float], stage: str) -> None:
        self.timings, self.stage = timings, stage

    def __enter__(self) -> None:
        self.start = time.perf_counter()

    def __exit__(self, *exc) -> None:
        self.timings[self.stage] += time.perf_counter() - self.start
