"""``degraded-truth``: the true pose corrupted by a configurable error model (privileged).

A dial for the accuracy curve, not an estimator: like ``truth`` it is handed the true pose
(:meth:`DegradedTruth.see`, by the wrapper) and never estimates anything. Each delivered pose
is ``z = x(t_m - latency) + bias + drift(d_m) + white``:

- **white**: independent Gaussian noise per measurement, ``noise_std`` (m, rad);
- **bias**: a constant offset per episode, drawn at reset, ``bias_std`` (m, rad);
- **drift**: a random walk in distance travelled, ``drift_std`` (m and rad per sqrt(m)), so
  its variance after ``d`` metres is ``drift_std**2 * d``;
- **update rate and latency**: a measurement every ``1 / rate_hz`` seconds (every step when
  ``rate_hz`` is None) of the pose ``latency_s`` seconds old; between measurements the last
  one is held;
- **dropouts**: each scheduled measurement is lost with ``dropout_probability``.

``scale`` multiplies the three noise levels (the accuracy curve's dial). The reported
covariance is the sum of the variances it adds (white + bias + drift at the measured pose's
distance) plus ``(motion_std * age)**2`` for the motion since the measured instant (age =
latency plus hold time): the motion is modelled as an unknown velocity of standard deviation
``motion_std`` (m/s, rad/s), which is conservative for a robot slower than that. With
``rate_hz`` None and no latency the covariance is exact (NEES chi-square with 3 dof).
Random draws come from the generator given to :meth:`seed` (by the wrapper's ``reset``).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Annotated, ClassVar

import numpy as np

from stsf_gym.estimators.base import PoseEstimator, SensorModel
from stsf_gym.geometry import wrap_angle
from stsf_gym.validation import NonNegative, Range, require

NAME = "degraded-truth"
#: Salt mixed into the episode seed, so the dial's draws differ from the env's own stream.
SEED_SALT = 0x5D1A1
#: Added to every variance, so that a dial at zero still reports a positive definite covariance.
VARIANCE_FLOOR = 1e-12


#: A (position in m, yaw in rad) pair of standard deviations (or their rates).
StdPair = tuple[NonNegative, NonNegative]


@dataclass(frozen=True)
class DegradedTruthSettings:
    """The error model (``degraded-truth.yaml``); pairs are (position, yaw)."""

    noise_std: StdPair  # m, rad: white noise per measurement
    bias_std: StdPair  # m, rad: a constant offset per episode
    drift_std: StdPair  # m, rad per sqrt(m) travelled: a random walk
    rate_hz: float | None  # measurements per second; None: every control step
    latency_s: NonNegative  # age of the true pose a measurement reports
    dropout_probability: Annotated[float, Range(ge=0, lt=1)]
    motion_std: StdPair  # m/s, rad/s: assumed motion during a measurement's age
    scale: NonNegative  # multiplies noise, bias and drift: the accuracy curve's dial

    def __post_init__(self) -> None:
        rate = self.rate_hz
        require(
            rate is None or (isinstance(rate, int | float) and math.isfinite(rate) and rate > 0),
            "rate_hz",
            f"must be a positive number or null, got {rate!r}",
        )


def _vector(pair: tuple[float, float], scale: float = 1.0) -> np.ndarray:
    """A (position, yaw) pair as the (x, y, yaw) vector."""
    return scale * np.asarray(pair, dtype=float)[[0, 0, 1]]


class DegradedTruth(PoseEstimator):
    """The true pose with white noise, bias, drift, rate, latency and dropouts (module doc)."""

    name = NAME
    settings_type: ClassVar[type] = DegradedTruthSettings
    sensors = ()
    privileged = True  # handed the true pose

    def __init__(self, settings: DegradedTruthSettings) -> None:
        super().__init__()
        self.settings = settings
        self.noise = _vector(settings.noise_std, settings.scale)
        self.bias_std = _vector(settings.bias_std, settings.scale)
        self.drift = _vector(settings.drift_std, settings.scale)
        self.motion = _vector(settings.motion_std)
        self.rate_hz, self.latency = settings.rate_hz, settings.latency_s
        self.dropout = settings.dropout_probability
        self.rng: np.random.Generator | None = None
        self.history: deque = deque()

    def seed(self, seed: int | None) -> None:
        """Start a new stream for ``seed``; ``None`` keeps the current one (fresh if none)."""
        if seed is not None:
            self.rng = np.random.default_rng([int(seed), SEED_SALT])
        elif self.rng is None:
            self.rng = np.random.default_rng()

    def reset(self, model: SensorModel, initial_pose, initial_cov) -> None:
        super().reset(model, initial_pose, initial_cov)
        self.seed(None)
        self.bias = self.rng.normal(0.0, self.bias_std)
        self.time = self.distance = self.next_time = 0.0
        self.walk = np.zeros(3)
        self.history.clear()
        self.held = (0.0, self.mean.copy(), self.cov.copy())  # measured time, pose, cov

    def see(self, true_pose: np.ndarray) -> None:
        """The true pose of the current step (privileged; called by the wrapper)."""
        self.truth = np.asarray(true_pose, dtype=float).copy()
        if not self.history:
            self.history.append((0.0, 0.0, self.truth, self.walk.copy()))

    def update(self, obs: dict, dt: float) -> tuple[np.ndarray, np.ndarray]:
        last_pose = self.history[-1][2]
        step = float(np.hypot(*(self.truth[:2] - last_pose[:2])))
        self.time += dt
        self.distance += step
        self.walk = self.walk + self.rng.normal(0.0, self.drift * math.sqrt(step))
        self.history.append((self.time, self.distance, self.truth, self.walk.copy()))
        while len(self.history) > 1 and self.history[1][0] <= self.time - self.latency + 1e-9:
            self.history.popleft()  # keep the newest pose at or before the measured instant
        if self.time + 1e-9 >= self.next_time:
            self.next_time += 1.0 / self.rate_hz if self.rate_hz else dt
            if self.rng.random() < self.dropout:
                self.counters["dropouts"] += 1
            else:
                self._measure()
        measured_at, pose, cov = self.held
        age = self.time - measured_at
        self.mean = pose.copy()
        self.cov = cov + np.diag((self.motion * age) ** 2)
        return self.mean, self.cov

    def _measure(self) -> None:
        measured_at, distance, pose, walk = self.history[0]
        white = self.rng.normal(0.0, self.noise)
        z = pose + self.bias + walk + white
        z[2] = wrap_angle(z[2])
        variance = self.noise**2 + self.bias_std**2 + self.drift**2 * distance + VARIANCE_FLOOR
        self.held = (measured_at, z, np.diag(variance))
        self.counters["updates"] += 1
