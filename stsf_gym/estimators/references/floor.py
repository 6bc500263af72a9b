"""Each episode's floor: the offline batch smoother over all of its measurements.

The graph of :mod:`.smoother` over the whole episode at once (every camera frame a pose, the
start prior, ``k``'s prior, every odometry leg and every board), solved by GTSAM's
Levenberg-Marquardt: each pose then uses the measurements before *and after* it, so no causal
estimator with these measurements and this model can do better on average. Boards are not
gated by a prediction (there is none): after a first solve those whose whitened error exceeds
the chi-square quantile of ``outlier_probability`` (3 dof) are dropped and the graph solved
again. The pose of a step between frames is its frame's pose with the leg since, the
calibration estimate applied: ``x_i (+) (Delta - J_c c)``.

A kidnap or an encoder spike breaks the odometry the floor trusts; a floor over a faulted
episode is no bound.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import gtsam
import numpy as np

from stsf_gym.estimators.base import SensorModel, chi_square_gate
from stsf_gym.estimators.references import factors
from stsf_gym.estimators.references.measurements import (
    CONSIDERED,
    LandmarkPose,
    OdometryLeg,
    considered_cov,
)
from stsf_gym.estimators.references.smoother import LandmarkPoses
from stsf_gym.estimators.settings import LandmarkPoseSettings
from stsf_gym.geometry import compose

OUTLIER_PROBABILITY = 0.999


@dataclass
class EpisodeMeasurements:
    """What the floor needs of an episode: the start prior, ``k``'s prior, per frame its leg
    and boards, and per record (the start, then each step) its frame and the leg since."""

    start: np.ndarray
    start_cov: np.ndarray
    considered_cov: np.ndarray
    legs: list[OdometryLeg] = field(default_factory=list)  # leg into frame i (i >= 1)
    boards: list[list[LandmarkPose]] = field(default_factory=lambda: [[]])
    records: list[tuple[int, OdometryLeg]] = field(default_factory=list)


class FloorRecorder:
    """Fed every step's observation like an estimator; keeps :class:`EpisodeMeasurements`."""

    def __init__(self, settings: LandmarkPoseSettings) -> None:
        self.settings = settings

    def reset(self, model: SensorModel, start, start_cov) -> None:
        """Start recording an episode of ``model`` at ``start`` with covariance ``start_cov``."""
        self.model, self.boards = model, LandmarkPoses(model, self.settings)
        self.data = EpisodeMeasurements(
            np.asarray(start, float),
            np.asarray(start_cov, float),
            considered_cov(model, self.settings.mount_std),
        )
        self.leg = OdometryLeg()
        self.data.records.append((0, OdometryLeg()))
        self.counters: dict[str, int] = {}

    def update(self, obs: dict) -> None:
        """Record one step: its wheel travel, and the boards of a new camera frame."""
        self.leg.add(self.model, *self.model.calibration.wheel_travel(obs["encoders"]))
        if int(obs["image_new"]):
            self.data.legs.append(self.leg)
            self.data.boards.append(self.boards(obs, _Tally()))
            self.leg = OdometryLeg()
        frame = len(self.data.boards) - 1
        self.data.records.append((frame, _copy(self.leg)))


def batch_floor(
    data: EpisodeMeasurements, covariances: bool = False
) -> tuple[np.ndarray, np.ndarray | None]:
    """The floor's pose at every record ``(N, 3)`` and, with ``covariances``, the marginal
    covariance (world axes) of every frame's pose ``(F, 3, 3)``."""
    graph = _graph(data, drop=set())
    result = _solve(graph, data)
    gate = chi_square_gate(OUTLIER_PROBABILITY, dof=3)
    drop = {
        (i, j)
        for i, boards in enumerate(data.boards)
        for j, board in enumerate(boards)
        if _whitened(board, result, i) > gate
    }
    if drop:
        graph = _graph(data, drop)
        result = _solve(graph, data)
    k = result.atVector(factors.CONSIDERED_KEY)
    frames = [
        factors.as_array(result.atPose2(factors.pose_key(i))) for i in range(len(data.boards))
    ]
    poses = np.array(
        [compose(frames[i], leg.delta - leg.by_calibration @ k[:3]) for i, leg in data.records]
    )
    if not covariances:
        return poses, None
    marginals = gtsam.Marginals(graph, result)
    covs = np.array(
        [
            factors.local_to_world_cov(pose, marginals.marginalCovariance(factors.pose_key(i)))
            for i, pose in enumerate(frames)
        ]
    )
    return poses, covs


def _graph(data: EpisodeMeasurements, drop: set[tuple[int, int]]) -> gtsam.NonlinearFactorGraph:
    graph = gtsam.NonlinearFactorGraph()
    graph.add(factors.pose_prior(0, data.start, data.start_cov))
    graph.add(factors.considered_prior(np.zeros(CONSIDERED), data.considered_cov))
    for i, leg in enumerate(data.legs):
        graph.add(factors.odometry_factor(i, i + 1, leg))
    for i, boards in enumerate(data.boards):
        for j, board in enumerate(boards):
            if (i, j) not in drop:
                graph.add(factors.landmark_factor(i, board))
    return graph


def _solve(graph: gtsam.NonlinearFactorGraph, data: EpisodeMeasurements) -> gtsam.Values:
    """Levenberg-Marquardt from dead reckoning."""
    values, pose = gtsam.Values(), data.start
    values.insert(factors.pose_key(0), factors.as_pose2(pose))
    for i, leg in enumerate(data.legs):
        pose = compose(pose, leg.delta)
        values.insert(factors.pose_key(i + 1), factors.as_pose2(pose))
    values.insert(factors.CONSIDERED_KEY, np.zeros(CONSIDERED))
    params = gtsam.LevenbergMarquardtParams()
    params.setMaxIterations(50)
    return gtsam.LevenbergMarquardtOptimizer(graph, values, params).optimize()


def _whitened(board: LandmarkPose, result: gtsam.Values, frame: int) -> float:
    error = board.residual(
        factors.as_array(result.atPose2(factors.pose_key(frame))),
        result.atVector(factors.CONSIDERED_KEY),
    )
    return float(error @ np.linalg.solve(board.noise, error))


def _copy(leg: OdometryLeg) -> OdometryLeg:
    return OdometryLeg(leg.delta.copy(), leg.cov.copy(), leg.by_calibration.copy())


class _Tally(dict):
    """Counters nobody reads (the recorder is no estimator)."""

    def __missing__(self, key: str) -> int:
        return 0
