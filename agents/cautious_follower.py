"""The path follower with an uncertainty rule: near a goal it slows down, and at the goal it waits
(within a budget) until its estimate is sure enough, then declares arrival.

The rule and its constants were chosen from the physics below before any comparison was run, and
are kept whatever the results: a learnt agent must beat the best script, not a naive one.

- **When is an estimate sure enough?** A declaration succeeds when the TRUE position is within
  the goal radius R = 0.25 m. The follower stops where its estimate says the goal is (3 cm along
  the path), so the miss is the estimate's error. For a Gaussian position error of standard
  deviation sigma per axis the miss distance is Rayleigh: P(success) = 1 - exp(-R^2 / 2 sigma^2).
  :data:`SIGMA_SHARE` = 0.45 (sigma <= 0.11 m) gives P >= 0.92; sigma is the largest standard
  deviation of the 2x2 position covariance in ``obs["pose_cov"]`` (the worst axis, so an
  elongated ellipse counts by its long side).
- **Is it worth waiting?** On the sparse suite the ATE of STSF and the EKF is about 0.3 m, above
  R: at sigma = 0.3 m the same stop succeeds with P = 1 - exp(-0.35) = 0.30. Standing still adds
  no odometry drift, and every frame with a board in view (the pan camera points at boards)
  shrinks sigma, so a wait can turn a coin toss into a near-certain stop where a board is in
  sight, and costs only time where none is.
- **How long?** :data:`MAX_WAIT_S` = 30 s a goal: 150 camera frames at 5 Hz, as long as 3.7 m of
  driving at the follower's 0.122 m/s. The suites' time limits (600-700 s) leave at least 230 s
  over the 330-370 s their longest routes take at that speed, and a route has at most two goals:
  60 s of waiting is a quarter of the spare. The wait also never takes more than half of the
  episode's time left (the observation's sensor timestamp against ``sim.max_episode_seconds``),
  so later goals keep time to be reached.
- **Slowing down**: within :data:`APPROACH_M` = 1.0 m of the goal (estimated, 4 goal radii, the
  last 8 s at 0.122 m/s) and while sigma is above the threshold, at most :data:`CREEP_SPEED` =
  0.06 m/s, half the nominal speed: twice the camera frames per metre for a board seen on the
  approach, for 8 s more a goal.
- **Waiting without declaring**: with the STOP entry (``task.stop_action``) it stands still
  with STOP off; under the stand-still declaration standing still would declare, so it turns on
  the spot at twice ``task.stop_yaw_rate`` instead (slow enough for the camera's pan to follow).
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np

from stsf_gym.agents.follower import PathFollower
from stsf_gym.agents.follower_agent import FollowerAgent

SIGMA_SHARE = 0.45  # declare once the largest position std is at most this share of the radius
MAX_WAIT_S = 30.0  # s of waiting at a goal at most (and at most half the episode's time left)
APPROACH_M = 1.0  # m before the goal (estimated) within which an unsure follower creeps ...
CREEP_SPEED = 0.06  # ... at most this fast (m/s)
WAIT_TURN = 2.0  # x task.stop_yaw_rate: the turn on the spot that waits without declaring


def position_sigma(pose_cov: np.ndarray) -> float:
    """The largest standard deviation (m) of the position part of a pose covariance (3x3, or its
    9 entries flat)."""
    cov = np.asarray(pose_cov, dtype=float).reshape(3, 3)[:2, :2]
    return float(math.sqrt(max(np.linalg.eigvalsh((cov + cov.T) / 2)[-1], 0.0)))


class CautiousFollower(PathFollower):
    """:class:`PathFollower` that declares only when ``sigma <= sigma_share * goal_radius`` or
    its wait at that goal is used up (see the module's docstring)."""

    def configure_caution(
        self, goal_radius: float, time_limit: float, wait_yaw_rate: float, control_dt: float
    ) -> None:
        """The task's numbers the rule reads: goal radius (m), time limit (s), the yaw rate
        (rad/s) that waits without declaring, the control period (s)."""
        self.threshold = SIGMA_SHARE * goal_radius
        self.time_limit, self.control_dt = time_limit, control_dt
        self.wait_yaw_rate = wait_yaw_rate
        self.sigma, self.time, self._waited, self._waiting_for = math.inf, 0.0, 0.0, None
        self._budget = MAX_WAIT_S

    def observe(self, pose_cov: np.ndarray, time: float) -> None:
        """This step's estimate uncertainty and simulated time (s)."""
        self.sigma, self.time = position_sigma(pose_cov), time

    def _sure(self) -> bool:
        return self.sigma <= self.threshold

    def _may_declare(self) -> bool:
        """Sure enough, or the wait at this goal used up (:data:`MAX_WAIT_S`, half the time
        left when it began)."""
        if self._sure():
            return True
        if self._waiting_for != self.goals_left:  # a goal it has not waited at yet
            self._waiting_for, self._waited = self.goals_left, 0.0
            self._budget = min(MAX_WAIT_S, 0.5 * max(self.time_limit - self.time, 0.0))
        return self._waited >= self._budget - 1e-9  # counted in control periods

    def _wait(self) -> np.ndarray:
        """Stand still (STOP off), or turn slowly on the spot without the STOP entry."""
        self._waited += self.control_dt
        w = 0.0 if self.stop_action else self.wait_yaw_rate
        return (np.array([0.0, w]) / self.scale).astype(np.float32)

    def _approach_speed(self, left: float, speed: float) -> float:
        """At most :data:`CREEP_SPEED` within :data:`APPROACH_M` of the goal while unsure."""
        return speed if self._sure() or left > APPROACH_M else min(speed, CREEP_SPEED)


class CautiousFollowerAgent(FollowerAgent):
    """``cautious-follower``: :class:`CautiousFollower` behind the follower's interface (the same
    options and decision interval)."""

    name = "cautious-follower"
    follower_class: type[CautiousFollower] = CautiousFollower

    def begin(self, env: gym.Env) -> None:
        """A cautious follower of this episode's path, told the task's settings."""
        cfg = env.unwrapped.config
        self.follower = self.follower_class.for_env(env, **self.options)
        self.follower.configure_caution(
            cfg.task.goal_radius,
            cfg.sim.max_episode_seconds,
            WAIT_TURN * cfg.task.stop_yaw_rate,
            cfg.sim.control_dt * self.decision_steps,
        )

    def act(self, obs) -> np.ndarray:
        """The follower's action, waiting while ``obs["pose_cov"]`` is unsure at a goal."""
        self.follower.observe(obs["pose_cov"], float(np.asarray(obs["encoders_time"]).ravel()[0]))
        return super().act(obs)

    def config(self) -> dict:
        """The follower's settings and the caution's constants."""
        caution = {"sigma_share": SIGMA_SHARE, "max_wait_s": MAX_WAIT_S}
        caution |= {"approach_m": APPROACH_M, "creep_speed": CREEP_SPEED, "wait_turn": WAIT_TURN}
        return {**super().config(), "caution": caution}

    def label(self) -> str:
        """``cautious-follower`` (``-k<steps>`` with a decision interval)."""
        return super().label().replace("follower", self.name, 1)
