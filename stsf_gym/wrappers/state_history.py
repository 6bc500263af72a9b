"""Late measurements fused at their own time: a short history of states, rewound and replayed.

A camera frame's result reaches the robot ``camera.latency`` after its exposure
(``obs["image_time"]`` older than ``obs["encoders_time"]``), by which time the estimator has
dead-reckoned past it. Fusing it as if it were current would place the measurement at the
wrong pose. As ``robot_localization`` does with its state and measurement history, the
estimator's state before each recent step is kept together with that step's observation;
a late frame rewinds the estimator to the state before the step that ended at the frame's
exposure, fuses the frame there, and replays the odometry (and any frame) of every step since:

    x_m^+ = update(x_{m-1}, z_m + frame),  x_k = update(x_{k-1}, z_k), k = m+1 .. n

A frame older than the history (``horizon_s``) is dropped and counted (``frames_too_late``).
Counters rewind with the state, so a replayed frame is counted once (``frames_late`` counts the
frames fused late); timings keep the cost of the replays.

:class:`EstimatorDriver` steps an estimator through this history when the camera has a
latency: :class:`~stsf_gym.wrappers.PoseEstimateWrapper` and
:func:`~stsf_gym.recording.replay.replay` both run it, so a replayed log gives the estimates the
live run gave.
"""

from __future__ import annotations

import collections
import copy
from dataclasses import dataclass

import numpy as np

from stsf_gym.estimators.base import PoseEstimator

TIME_EPS = 1e-6
#: Observation keys that belong to a camera frame (whichever camera mode).
FRAME_KEYS = ("image", "landmark_ids", "landmark_points", "camera_pan_tilt", "image_time")


@dataclass
class _Step:
    time: float  # s: the end of the step (its encoders' timestamp)
    before: PoseEstimator  # the estimator's state before the step
    obs: dict  # the observation the step was fused with
    dt: float


class StateHistory:
    """The states of the last ``horizon_s`` seconds and the observations they were updated
    with; :meth:`update` returns the live estimator (a rewound copy after a late frame)."""

    def __init__(self, horizon_s: float) -> None:
        self.horizon_s = horizon_s
        self._steps: collections.deque[_Step] = collections.deque()

    def reset(self, estimator: PoseEstimator, obs: dict) -> None:
        """Start from the reset estimator: the reset is a step of no motion, so a frame exposed
        then can be fused at it."""
        still = {**obs, "encoders": np.zeros_like(obs["encoders"]), "image_new": 0}
        self._steps = collections.deque(
            [_Step(float(obs["encoders_time"][0]), _snapshot(estimator), still, 0.0)]
        )

    def update(
        self, estimator: PoseEstimator, obs: dict, dt: float
    ) -> tuple[PoseEstimator, np.ndarray, np.ndarray]:
        """Fold ``obs`` into ``estimator`` (at the frame's own time when it is late); returns
        the estimator to keep and its mean and covariance now."""
        now = float(obs["encoders_time"][0])
        exposure = float(obs["image_time"][0])
        late = bool(obs["image_new"]) and exposure < now - TIME_EPS
        if late:
            estimator = self._fuse_late(estimator, obs, exposure)
            obs = {**obs, "image_new": 0}  # this step's own odometry, the frame already in
        self._steps.append(_Step(now, _snapshot(estimator), obs, dt))
        mean, cov = estimator.update(obs, dt)
        while self._steps and self._steps[0].time < now - self.horizon_s - TIME_EPS:
            self._steps.popleft()
        return estimator, mean, cov

    def _fuse_late(self, estimator: PoseEstimator, obs: dict, exposure: float) -> PoseEstimator:
        """Rewind to the step that ended at ``exposure``, fuse the frame there, replay."""
        index = next(
            (i for i, step in enumerate(self._steps) if abs(step.time - exposure) <= TIME_EPS),
            None,
        )
        if index is None:  # older than the history (or not at a step end): cannot be placed
            estimator.counters["frames_too_late"] += 1
            return estimator
        live = _snapshot(self._steps[index].before)
        live.timings = estimator.timings  # the replays' cost counts
        for counter in ("frames_late", "frames_too_late"):  # counts of the history itself
            live.counters[counter] = estimator.counters[counter]
        frame = {key: obs[key] for key in FRAME_KEYS if key in obs}
        for i in range(index, len(self._steps)):
            step = self._steps[i]
            if i == index:
                step.obs = {**step.obs, **frame, "image_new": 1}
            step.before = _snapshot(live)
            live.update(step.obs, step.dt)
        live.counters["frames_late"] += 1
        return live


def _snapshot(estimator: PoseEstimator) -> PoseEstimator:
    """A copy of ``estimator``'s state sharing its (immutable) sensor model."""
    memo = {id(estimator.model): estimator.model, id(estimator.timings): estimator.timings}
    return copy.deepcopy(estimator, memo)


def history_horizon(delay_s: float, jitter_s: float, control_dt: float) -> float | None:
    """How far back (s) a late frame can be fused for a camera latency of ``delay_s`` with
    jitter ``jitter_s``; ``None`` without latency (no history kept)."""
    if delay_s + jitter_s > 0:
        return delay_s + 5 * jitter_s + 2 * control_dt
    return None


class EstimatorDriver:
    """Starts and updates ``estimator``, through a history of ``horizon_s`` seconds when
    frames may arrive late (``None``: every frame fused when it arrives)."""

    def __init__(self, estimator: PoseEstimator, horizon_s: float | None = None) -> None:
        self.estimator = estimator
        self.history = None if horizon_s is None else StateHistory(horizon_s)

    def start(self, obs: dict, true_pose: np.ndarray | None) -> None:
        """Begin the episode at the (already reset) estimator with the start's observation."""
        if self.history is not None:
            self.history.reset(self.estimator, obs)
        self._show_truth(true_pose)

    def update(
        self, obs: dict, dt: float, true_pose: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Fold one step's ``obs`` (``dt`` seconds after the last) into the estimate; returns
        its mean and covariance."""
        self._show_truth(true_pose)
        if self.history is None:
            return self.estimator.update(obs, dt)
        self.estimator, mean, cov = self.history.update(self.estimator, obs, dt)
        return mean, cov

    def _show_truth(self, true_pose: np.ndarray | None) -> None:
        """Hand a privileged source the step's true pose (other sources are never shown it)."""
        if self.estimator.privileged:
            if true_pose is None:
                raise ValueError(f"{self.estimator.name}: a privileged source needs the true pose")
            self.estimator.see(true_pose)
