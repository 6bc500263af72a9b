"""The cautious follower that acts to localize: near a goal, while its estimate is unsure, it goes
to see the map's nearest board, waits there until the estimate is sure (or a budget ends), returns
and declares.

The rule and its constants were fixed from the physics below before any comparison was run, and
are kept whatever the results: the scripted reference a learnt agent must beat where the
estimate is poor.

- **When**: exactly where the cautious follower would wait
  (:mod:`~stsf_gym.agents.cautious_follower`): its estimate at the goal, the largest position
  standard deviation above ``SIGMA_SHARE`` = 0.45 of the goal radius (0.11 m: a declaration
  then succeeds with P < 0.92). Waiting alone helps only where a board is in view: on the
  sparse suite the deviation at the stop stays 0.28-0.29 m and the cautious follower gains
  nothing on STSF (DESIGN.md, facts of 2026-12-01).
- **Seeing from here**: a board is *in sight* where the camera's pointing could hold it
  (:class:`~stsf_gym.estimators.camera_pointing.LandmarkPointer`: 1-8 m, facing the camera
  within 65 deg of its normal, no wall of the map across the line of sight). One in sight from
  the estimated position but beyond the pan limit is brought into it by turning on the spot
  (at the follower's 0.6 rad/s, until the board is :data:`PAN_MARGIN_DEG` inside the limit):
  turning moves the position by nothing, so it costs no drift.
- **Going to see**: with no board in sight from here, the nearest point of the route within
  :data:`MAX_DETOUR_M` = 1.5 m of the goal (before or past it, searched every
  :data:`VIEW_STEP_M` = 0.25 m) from which one is in sight. Why 1.5 m: driving adds drift, and
  the drive back after seeing must not spend what seeing bought. The encoders are calibrated
  so that odometry drifts about 4 % of the distance (40 cm over 10 m, sect. 4.3); a board
  seen at 1-3 m puts the STSF/EKF position within about 5 cm (Table I's errors shrink with
  range: 0.11-0.14 m at 5-7 m), and 0.05 m + 4 % of 1.5 m = 0.11 m, the threshold.
- **How long**: the cautious follower's budget (``MAX_WAIT_S`` = 30 s of looking a goal, at
  most half the episode's time left); the detour's driving is at most 2 x 1.5 m, 25 s at the
  nominal speed. Looking ends when the estimate is sure or the budget is spent; it then drives
  back to the goal (where its estimate says the goal is) and declares there, sure or not.
- No board in sight from here nor from any point within the detour: it waits as the cautious
  follower does.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np

from stsf_gym.agents.cautious_follower import CautiousFollower, CautiousFollowerAgent
from stsf_gym.estimators.camera_pointing import LandmarkPointer
from stsf_gym.wrappers.sensor_model import robot_map

MAX_DETOUR_M = 1.5  # m along the route from the goal within which a viewpoint is sought
VIEW_STEP_M = 0.25  # m between the route points tried as viewpoints (a goal radius)
PAN_MARGIN_DEG = 10.0  # a board this far inside the pan limit needs no turn
ARRIVED_M = 0.05  # m along the route: at a viewpoint, or back at the goal

LOOK, THERE, BACK, RETURNED = "look", "there", "back", "returned"  # phases at an unsure goal


class ActiveFollower(CautiousFollower):
    """:class:`CautiousFollower` that turns or drives to see a board where it would wait (see
    the module's docstring)."""

    def configure_activity(self, pointer: LandmarkPointer) -> None:
        """The map's boards and walls as the camera's pointing sees them."""
        self.pointer = pointer
        self.pan_margin = math.radians(PAN_MARGIN_DEG)
        self._phase: str | None = None
        self._phase_goal: int | None = None  # the goal (its goals_left) the phase belongs to
        self._view_arc: float | None = None
        self.detours = 0  # goals at which it drove to a viewpoint (for the behaviour report)

    def _drive(self, pose: np.ndarray, sonar: np.ndarray | None) -> np.ndarray:
        self._pose, self._sonar = np.asarray(pose, dtype=float), sonar
        if self._phase in (THERE, BACK) and self._phase_goal == self.goals_left:
            self._declared = False
            return self._detour()
        return super()._drive(pose, sonar)

    def _may_declare(self) -> bool:
        """Sure, back from a detour, or the look at this goal spent (as the cautious rule)."""
        if self._phase_goal != self.goals_left:  # a goal not acted at yet
            self._phase_goal, self._phase = self.goals_left, None
        if self._phase == RETURNED or self._sure():
            return True
        return super()._may_declare() and self._phase != THERE

    def _wait(self) -> np.ndarray:
        """At the unsure goal: turn toward a board in sight, or set off for a viewpoint, or
        stand (the cautious follower's wait)."""
        if self._phase is None:
            self._view_arc = None if self._sight() else self._viewpoint()
            self._phase = LOOK if self._view_arc is None else THERE
            self.detours += int(self._phase == THERE)
        if self._phase == THERE:
            return self._detour()
        self._waited += self.control_dt
        return self._look()

    def _look(self) -> np.ndarray:
        """Turn on the spot toward the nearest board in sight until it is within the pan
        limit (less the margin); else stand still, STOP off (as the cautious follower)."""
        sighted = self._sight()
        if sighted:
            _, bearing = min(sighted, key=lambda s: self._range(s[0]))
            if abs(bearing) > self.pointer.pan_limit - self.pan_margin:
                w = math.copysign(self.cfg.max_yaw_rate, bearing)
                return (np.array([0.0, w]) / self.scale).astype(np.float32)
        return super()._wait()

    def _detour(self) -> np.ndarray:
        """Drive to the viewpoint and look there; once sure or the look is spent, drive back to
        the goal and declare there."""
        along = self.path.project(self._pose)
        if self._phase == THERE and self._view_arc is not None:
            if abs(along - self._view_arc) > ARRIVED_M:
                return self._go_to(self._view_arc)
            if not self._sure() and self._waited < self._budget - 1e-9:
                self._waited += self.control_dt
                return self._look()
            self._phase = BACK
        goal = self.goals[self._goal]
        if abs(along - goal) > ARRIVED_M:
            return self._go_to(goal)
        self._phase = RETURNED  # declared at the next step, where the estimate says the goal is
        return np.zeros(2, np.float32)

    def _go_to(self, arc: float) -> np.ndarray:
        """Pure pursuit to the route's point ``arc`` metres along it, slowing as it nears."""
        target = self.path.point_at(arc)
        distance = float(np.hypot(*(target - self._pose[:2])))
        arrival = self.cfg.arrival
        speed = min(max(arrival.approach_gain * distance, arrival.min_speed), self.cfg.speed)
        return self._pursue(self._pose, target, speed, self._sonar)

    def _sight(self, pose: np.ndarray | None = None) -> list[tuple[int, float]]:
        return self.pointer.in_sight(self._pose if pose is None else pose)

    def _range(self, index: int) -> float:
        return float(np.hypot(*(self.pointer.centre(index) - self._pose[:2])))

    def _viewpoint(self) -> float | None:
        """The arc length of the route point nearest the goal, within :data:`MAX_DETOUR_M`,
        from which a board is in sight (None: none)."""
        goal = self.goals[self._goal]
        steps = round(MAX_DETOUR_M / VIEW_STEP_M)
        for offset in sorted((k * VIEW_STEP_M for k in range(-steps, steps + 1)), key=abs):
            arc = goal + offset
            if offset == 0 or not 0.0 <= arc <= self.path.length:
                continue
            x, y = self.path.point_at(arc)
            if self._sight(np.array([x, y, self.path.heading_at(arc)])):
                return arc
        return None


class ActiveFollowerAgent(CautiousFollowerAgent):
    """``active-follower``: :class:`ActiveFollower` behind the follower's interface."""

    name = "active-follower"
    follower_class = ActiveFollower

    def begin(self, env: gym.Env) -> None:
        """An active follower of this episode's path, told the task's settings and the map."""
        super().begin(env)
        landmarks, walls = robot_map(env)
        robot = env.unwrapped.config.robot  # type: ignore[attr-defined]
        pointer = LandmarkPointer(
            landmarks, walls, robot.camera_forward, math.radians(robot.pan_limit_deg)
        )
        follower = self.follower
        assert isinstance(follower, ActiveFollower)
        follower.configure_activity(pointer)

    def config(self) -> dict:
        """The cautious follower's settings and the activity's constants."""
        activity = {"max_detour_m": MAX_DETOUR_M, "view_step_m": VIEW_STEP_M}
        activity |= {"pan_margin_deg": PAN_MARGIN_DEG, "arrived_m": ARRIVED_M}
        return {**super().config(), "activity": activity}
