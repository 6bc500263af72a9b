"""Monte Carlo localization as ROS's AMCL does it (Thrun, Burgard and Fox, *Probabilistic
Robotics*, ch. 8; Fox 2003, KLD-sampling).

**Particles** ``x^(i) = [x, y, yaw]``, each with its own considered parameters ``k^(i)``
(:mod:`.measurements`: wheel radii and wheelbase ``c``, camera mount, camera heading and focal
scale; drawn from their prior ``N(0, Sigma_k)``): these errors are per-episode constants, so a
particle carries one hypothesis of them instead of the filter spreading a systematic error as
white noise, and the particles whose hypothesis fits survive.

**Motion** (every step, :func:`sample_motion`): each particle's wheels roll the reported travel
corrected by its calibration, ``d (1 - c)``, plus slip ``N(0, (odometry_inflation)^2 var(d))``
(the wheel noise model, inflated), then the mid-point model.

**Measurement** (when the robot has moved ``update_min_d`` or turned ``update_min_a`` since the
last one, AMCL's rule against counting one view many times; with ``board_updates:
every-frame`` the boards of every frame in between too), particle weights multiply by

- the sonar ring's likelihood field (:mod:`.likelihood_field`): ``sonar_beams`` readings
  evenly spread over the ring (AMCL's ``max_beams``), those below ``sonar_max_range`` (AMCL's
  ``laser_max_range``: past 2 m a 25 degree cone is too wide for its echo's point to be put on
  its axis), each ``N(d; 0, sonar_std^2)`` in its end point's distance ``d`` to the walls;
- every map board seen in this step's camera frame: its PnP pose ``z`` in the robot frame
  (:class:`~.measurements.LandmarkPose`, the smoother's measurement, floors included) against
  ``h(x) + M k``: ``p = exp(-0.5 e^T R^-1 e) + landmark_outlier``, ``e = h(x) + M k - z``;
  ``landmark_outlier`` keeps a misread id from killing the right particles.

**Augmented MCL** (Probabilistic Robotics, table 8.3), driven by the boards: with ``w_avg``
the particles' mean likelihood per board seen in the frame,
``w_slow <- w_slow + alpha_slow (w_avg - w_slow)`` and ``w_fast`` alike with ``alpha_fast``
(both start at a consistent filter's mean, :data:`EXPECTED_BOARD_LIKELIHOOD`); at resampling
each new particle is replaced with probability ``max(0, 1 - w_fast / w_slow)`` by one drawn
from the poses the frame's boards give (``L (+) (-) z`` with its covariance: Mixture MCL's
dual proposal, Thrun et al. 2001): uniform over a 24 m corridor a random particle would
almost never land near the robot. When the boards stop fitting (a kidnap), such particles
come in, and those that fit the sonar and the next boards take over. The sonar ring
weighs the particles but does not drive the injection: in a corridor it fits a robot
carried along the corridor as well.

**Resampling** when the effective sample size ``1 / sum w^2`` falls below
``resample_threshold`` times the count, or particles are to be injected: low-variance
(systematic) draws, in random order, kept
until their number reaches the KLD bound for the number ``k`` of occupied bins
(``bin_size_xy`` by ``bin_size_xy`` by ``bin_size_yaw``)::

    n = (k - 1) / (2 eps) (1 - 2 / (9 (k - 1)) + sqrt(2 / (9 (k - 1))) z)^3

(``eps`` = ``kld_error``, ``z`` the ``kld_quantile`` of the normal), within
``[min_particles, particles]``. **Roughening** (Gordon, Salmond and Smith 1993): the drawn
particles are then jittered by ``N(0, diag(sigma^2))``, ``sigma_j = K E_j n^(-1/3)`` with
``K`` = ``roughening``, ``E_j`` the drawn cloud's extent (max - min) in ``x``, ``y`` and heading
and ``n`` their count: the slip between two frames spreads copies of one particle by well
under a millimetre, less than the boards' information narrows the cloud, so without it the
cloud holds few distinct poses and its covariance understates the error.

**Output**: the weighted mean (heading by its mean sine and cosine) and weighted covariance.
**Unknown start**: ``prior: free-space``, or the wrapper's ``reset(options={"unknown_start":
True})`` (:meth:`spread_prior`), spreads the particles uniformly over the free space and every
heading. The sonar alone can settle such a cloud on the wrong one of two places that echo
alike (the corridor's two ends), as narrow as a right one, so ``confirmed`` says whether a map
board has agreed with the estimate since: its own pose within the chi-square gate
(``gate_probability``, 3 dof) of the estimate, their covariances added.
``counters``: ``frames``, ``frames_matched``, ``landmark_updates``, ``updates``,
``resampled``, ``injected``.
"""

from __future__ import annotations

import math
from typing import ClassVar, NamedTuple

import numpy as np
from scipy.special import ndtri

from stsf_gym.estimators.base import PoseEstimator, SensorModel, chi_square_gate
from stsf_gym.estimators.frame_detector import FrameDetector
from stsf_gym.estimators.landmark_observation import observe, robot_pose_from_landmark
from stsf_gym.estimators.references.likelihood_field import LikelihoodField
from stsf_gym.estimators.references.measurements import (
    CONSIDERED,
    LandmarkPose,
    considered_cov,
    landmark_pose,
)
from stsf_gym.estimators.settings import MCLSettings
from stsf_gym.geometry import compose, inverse, wrap_angle

#: ``E[exp(-chi^2_3 / 2)] = 2^(-3/2)``: a board's mean likelihood under a consistent filter,
#: where augmented MCL's averages start.
EXPECTED_BOARD_LIKELIHOOD = 2**-1.5
COV_FLOOR = 1e-8  # added to the reported covariance's diagonal (one particle left)


class Board(NamedTuple):
    """A map board seen in a frame: the measurement, the information ``R^-1`` of its ``z``,
    and the robot pose it gives with that pose's covariance."""

    measurement: LandmarkPose
    information: np.ndarray
    pose: np.ndarray
    cov: np.ndarray


class MonteCarloLocalization(PoseEstimator):
    """AMCL: KLD-sampling, augmented MCL, sonar likelihood field and map boards.

    Settings (:class:`MCLSettings`, ``configs/estimators/mcl.yaml``).
    """

    name = "mcl"
    sensors = ("encoders", "camera")  # map boards in the camera frames
    settings_type: ClassVar[type] = MCLSettings

    def __init__(self, settings: MCLSettings) -> None:
        super().__init__()
        self.settings = settings
        self.rng = np.random.default_rng(0)
        self.field: LikelihoodField | None = None
        self._field_key: tuple | None = None
        self.gate = chi_square_gate(settings.gate_probability, dof=3)

    def believed_odometry(self) -> MCLSettings:
        """Its settings: the particles' motion noise is the odometry's it believes."""
        return self.settings

    def seed(self, seed: int | None) -> None:
        """Seed the particles' draws (the wrapper passes ``reset(seed=...)``'s)."""
        if seed is not None:
            self.rng = np.random.default_rng([seed, 0x4D434C])

    def reset(self, model: SensorModel, initial_pose, initial_cov) -> None:
        super().reset(model, initial_pose, initial_cov)
        s = self.settings
        key = (np.asarray(model.walls).tobytes(), model.wall_thickness, model.body_radius)
        if key != self._field_key:  # a new world: a new field
            self.field = LikelihoodField(model, s.field_resolution, self.mean)
            self._field_key = key
        self.detector = FrameDetector(model.pattern, set(model.landmarks), model.camera_calibration)
        self.considered_cov = considered_cov(model, s.mount_std)
        self.w_slow = self.w_fast = EXPECTED_BOARD_LIKELIHOOD
        self.moved = np.zeros(2)
        self.confirmed = True
        if s.prior == "free-space":
            self.spread_prior()
        else:
            self._set(self.rng.multivariate_normal(self.mean, self.cov, s.particles))

    def spread_prior(self) -> None:
        """Forget the start: particles uniform over the free space and every heading."""
        self._set(self.field.sample_free(self.settings.particles, self.rng))
        self.confirmed = False

    def _set(self, poses: np.ndarray) -> None:
        n = len(poses)
        self.poses = poses
        self.poses[:, 2] = wrap_angle(self.poses[:, 2])
        self.considered = self._draw_considered(n)
        self.log_w = np.full(n, -math.log(n))
        self._estimate()

    def _draw_considered(self, count: int) -> np.ndarray:
        return self.rng.multivariate_normal(np.zeros(CONSIDERED), self.considered_cov, count)

    def update(self, obs: dict, dt: float) -> tuple[np.ndarray, np.ndarray]:
        with self.timed("odometry"):
            travel = self.model.calibration.wheel_travel(obs["encoders"])
            self.sample_motion(*travel)
            wheelbase = self.model.calibration.wheelbase
            self.moved += np.abs([travel.mean(), (travel[1] - travel[0]) / wheelbase])
        boards = []
        if int(obs.get("image_new", 0)):
            with self.timed("detect"):
                boards = self._boards(obs)
        s = self.settings
        sonar = obs.get("sonar")
        if self.moved[0] >= s.update_min_d or self.moved[1] >= s.update_min_a:
            self.moved[:] = 0.0
        elif s.board_updates == "every-frame" and boards:
            sonar = None  # the boards' update alone
        else:
            return self.mean, self.cov
        with self.timed("update"):
            self.weigh(sonar, boards)
        return self.mean, self.cov

    def sample_motion(self, d_left: float, d_right: float) -> None:
        """Each particle's wheels: the travel its calibration corrects, plus inflated slip."""
        n = len(self.poses)
        std = np.sqrt(self.model.odometry_noise.slip_variances(d_left, d_right))
        wheels = np.array([d_left, d_right]) * (1 - self.considered[:, :2])
        wheels = wheels + self.rng.normal(size=(n, 2)) * std * self.settings.odometry_inflation
        distance = wheels.mean(axis=1)
        turn = (wheels[:, 1] - wheels[:, 0]) / self.model.calibration.wheelbase
        turn = turn * (1 + self.considered[:, 2])
        mid = self.poses[:, 2] + turn / 2
        self.poses[:, 0] += distance * np.cos(mid)
        self.poses[:, 1] += distance * np.sin(mid)
        self.poses[:, 2] = wrap_angle(self.poses[:, 2] + turn)
        self._estimate()

    def _boards(self, obs: dict) -> list[Board]:
        """Every usable board of the frame: a finite PnP pose (near a fronto-parallel view
        OpenCV's IPPE can report success with a NaN rotation, which the Kalman estimators'
        gates reject) within ``min_range`` and ``max_range``."""
        s, found = self.settings, []
        pan, tilt = (float(a) for a in obs["camera_pan_tilt"])
        detections = self.detector(obs)
        self.counters["frames"] += 1
        self.counters["frames_matched"] += bool(detections)
        for detection in detections:
            seen = observe(detection, self.model, pan, tilt, s.sigma_px)
            if seen is None or not np.isfinite([*seen.z, *seen.cov.ravel()]).all():
                continue
            if not s.min_range <= math.hypot(*seen.z[:2]) <= s.max_range:
                continue
            measurement = landmark_pose(
                seen, s.position_std_floor, s.position_std_per_m, s.orientation_std_floor
            )
            found.append(
                Board(
                    measurement,
                    np.linalg.inv(measurement.noise),
                    *robot_pose_from_landmark(seen.landmark, seen.z, measurement.noise),
                )
            )
        return found

    def weigh(self, sonar, boards: list[Board]) -> None:
        """Measurement update, augmented MCL's averages, and resampling when due."""
        log_l, s = np.zeros(len(self.poses)), self.settings
        if sonar is not None and self.model.sonar is not None:
            log_l += self._sonar_log_likelihood(np.asarray(sonar, dtype=float)).sum(axis=1)
        if boards:
            board_log_l = np.zeros(len(self.poses))
            for board in boards:
                seen = board.measurement
                error = compose(inverse(self.poses), seen.landmark_pose) - seen.z
                error += self.considered @ seen.by_considered.T
                error[:, 2] = wrap_angle(error[:, 2])
                d2 = np.einsum("ni,ij,nj->n", error, board.information, error)
                board_log_l += np.log(np.exp(-0.5 * d2) + s.landmark_outlier)
            self.counters["landmark_updates"] += len(boards)
            log_l += board_log_l
            w_avg = float(np.exp(board_log_l / len(boards) + self.log_w).sum())
            self.w_slow += s.alpha_slow * (w_avg - self.w_slow)
            self.w_fast += s.alpha_fast * (w_avg - self.w_fast)
        self.counters["updates"] += 1
        self.log_w = self.log_w + log_l
        self.log_w -= np.logaddexp.reduce(self.log_w)
        depleted = 1.0 / np.exp(2 * self.log_w).sum() < s.resample_threshold * len(self.poses)
        if depleted or (boards and self.w_fast < self.w_slow):  # or particles to inject
            self.resample(boards)
        self._estimate()
        if boards and not self.confirmed:
            self.confirmed = any(self._agrees(board) for board in boards)

    def _agrees(self, board: Board) -> bool:
        """The board's own robot pose within the gate of the estimate."""
        offset = board.pose - self.mean
        offset[2] = wrap_angle(offset[2])
        return float(offset @ np.linalg.solve(board.cov + self.cov, offset)) <= self.gate

    def used_beams(self, count: int) -> np.ndarray:
        """Indices of the ``sonar_beams`` readings, evenly spread over a ring of ``count``."""
        return np.linspace(0, count, self.settings.sonar_beams, endpoint=False).astype(int)

    def end_points(self, poses: np.ndarray, ranges: np.ndarray, beams: np.ndarray) -> np.ndarray:
        """World end points (poses x beams x 2) of the readings ``ranges[beams]`` taken from
        each of ``poses`` (n x 3), each on its transducer's axis."""
        sonar = self.model.sonar
        heading = poses[:, 2:3] + sonar.axes[beams]
        reach = sonar.ring_radius + ranges[beams]
        return poses[:, None, :2] + reach[:, None] * np.stack(
            [np.cos(heading), np.sin(heading)], -1
        )

    def _sonar_log_likelihood(self, ranges: np.ndarray) -> np.ndarray:
        """Log likelihood (particles x readings) of the used readings that echoed within
        ``sonar_max_range``."""
        sonar, s = self.model.sonar, self.settings
        beams = self.used_beams(len(ranges))
        beams = beams[ranges[beams] < min(sonar.max_range - 1e-6, s.sonar_max_range)]
        distance = self.field.distance(self.end_points(self.poses, ranges, beams))
        hit = np.exp(-0.5 * (distance / s.sonar_std) ** 2) / (math.sqrt(math.tau) * s.sonar_std)
        return np.log((1 - s.sonar_random) * hit + s.sonar_random / sonar.max_range)

    def resample(self, boards: list[Board]) -> None:
        """Low-variance draws in random order, as many as KLD-sampling asks; with augmented
        MCL's probability a draw is replaced by one from the frame's boards' poses."""
        ceiling = self.settings.particles
        weights = np.exp(self.log_w)
        positions = (self.rng.random() + np.arange(ceiling)) / ceiling
        drawn = np.minimum(np.searchsorted(np.cumsum(weights), positions), len(weights) - 1)
        drawn = self.rng.permutation(drawn)
        poses, considered = self.poses[drawn], self.considered[drawn]
        inject = max(0.0, 1.0 - self.w_fast / self.w_slow) if boards else 0.0
        random = self.rng.random(ceiling) < inject
        poses[random] = self._sample_boards(boards, int(random.sum()))
        considered[random] = self._draw_considered(int(random.sum()))
        count = self._kld_count(poses)
        self.counters["resampled"] += 1
        self.counters["injected"] += int(random[:count].sum())
        poses, drawn_here = poses[:count], ~random[:count]
        poses[drawn_here] = self._roughened(poses[drawn_here])
        self.poses, self.considered = poses, considered[:count]
        self.log_w = np.full(count, -math.log(count))

    def _roughened(self, poses: np.ndarray) -> np.ndarray:
        """Gordon's roughening of the drawn poses (heading extent taken around the mean)."""
        if not self.settings.roughening or len(poses) < 2:
            return poses
        offsets = poses - self.mean
        offsets[:, 2] = wrap_angle(offsets[:, 2])
        extent = offsets.max(axis=0) - offsets.min(axis=0)
        sigma = self.settings.roughening * extent * len(poses) ** (-1 / 3)
        poses = poses + self.rng.normal(size=poses.shape) * sigma
        poses[:, 2] = wrap_angle(poses[:, 2])
        return poses

    def _sample_boards(self, boards: list[Board], count: int) -> np.ndarray:
        """``count`` poses, each from a random board's robot pose and covariance."""
        which = self.rng.integers(len(boards), size=count)
        poses = np.empty((count, 3))
        for i, board in enumerate(boards):
            chosen = which == i
            poses[chosen] = self.rng.multivariate_normal(board.pose, board.cov, int(chosen.sum()))
        poses[:, 2] = wrap_angle(poses[:, 2])
        return poses

    def _kld_count(self, poses: np.ndarray) -> int:
        """The fewest leading particles whose count reaches the KLD bound of their bins."""
        s = self.settings
        size = np.array([s.bin_size_xy, s.bin_size_xy, s.bin_size_yaw])
        bins = np.floor(poses / size).astype(np.int64)
        _, first = np.unique(bins, axis=0, return_index=True)
        occupied = np.searchsorted(np.sort(first), np.arange(len(poses)), side="right")
        k = np.maximum(occupied - 1, 1)
        a = 2.0 / (9.0 * k)
        bound = k / (2 * s.kld_error) * (1 - a + np.sqrt(a) * ndtri(s.kld_quantile)) ** 3
        enough = np.flatnonzero(np.arange(1, len(poses) + 1) >= np.maximum(bound, s.min_particles))
        return int(enough[0]) + 1 if len(enough) else len(poses)

    def _estimate(self) -> None:
        w = np.exp(self.log_w - np.logaddexp.reduce(self.log_w))
        heading = math.atan2(w @ np.sin(self.poses[:, 2]), w @ np.cos(self.poses[:, 2]))
        mean = np.array([w @ self.poses[:, 0], w @ self.poses[:, 1], heading])
        offsets = self.poses - mean
        offsets[:, 2] = wrap_angle(offsets[:, 2])
        self.mean = mean
        self.cov = (offsets * w[:, None]).T @ offsets + np.eye(3) * COV_FLOOR
