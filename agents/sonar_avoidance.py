"""Sonar collision avoidance: a reactive layer that bends a path follower's command around
obstacles seen by the sonar ring (a free-heading scheme in the spirit of the vector field
histogram, with the robot's width taken into account)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from stsf_gym.geometry import compiled


@dataclass(frozen=True)
class AvoidanceConfig:
    """The follower's sonar avoidance (``avoidance:`` in ``configs/agents/follower.yaml``)."""

    enabled: bool
    margin: float  # m added to the body radius: half-width of the lane a heading must keep free
    horizon: float  # m of free lane that makes a heading clear
    slow_distance: float  # m free straight ahead below which the speed falls linearly ...
    stop_distance: float  # ... to zero at this distance, where the robot turns on the spot
    sector_deg: float  # candidate headings lie within +- this of the robot's heading
    step_deg: float  # spacing of the candidate headings
    gain: float  # yaw rate (rad/s) per radian between the heading and the chosen free heading

    def __post_init__(self) -> None:
        if not 0 <= self.stop_distance < self.slow_distance:
            raise ValueError(
                f"avoidance needs 0 <= stop_distance < slow_distance, got "
                f"{self.stop_distance}, {self.slow_distance}"
            )
        if self.horizon <= 0 or self.margin < 0 or self.gain <= 0:
            raise ValueError("avoidance horizon and gain must be positive, margin non-negative")
        if not 0 < self.step_deg <= self.sector_deg <= 180:
            raise ValueError(
                f"avoidance needs 0 < step_deg <= sector_deg <= 180, got "
                f"{self.step_deg}, {self.sector_deg}"
            )


class SonarAvoidance:
    """Keep the path follower's command unless the sonar shows its heading blocked.

    Each sonar reading below ``max_range`` is an obstacle point on its transducer's axis
    (transducer 0 forward, the rest counter-clockwise), the reading plus the body radius from
    the robot's centre (the ring sits on the body; the 25 degree cone is not spread out, as in
    the vector field histogram). A heading is *free* for the distance the robot, widened by
    ``margin`` each side, can drive straight along it before touching a point.

    While the follower's heading (the bearing of its pure-pursuit target) is free for
    ``horizon`` metres its command passes unchanged, so walls beside the path do not
    interfere. Otherwise the robot turns, with yaw rate ``gain`` times the angle, towards the
    candidate heading within ``sector_deg`` that is free for ``horizon`` and nearest the
    follower's (the freest one if none is), and slows linearly from full speed at
    ``slow_distance`` of free lane straight ahead to a stop, turning on the spot, at
    ``stop_distance``. Once the path heading clears again, pure pursuit takes over.
    """

    def __init__(
        self, cfg: AvoidanceConfig, sonar_count: int, body_radius: float, max_range: float
    ) -> None:
        self.cfg = cfg
        self.axes = np.arange(sonar_count) * math.tau / sonar_count
        self._axis_units = np.column_stack([np.cos(self.axes), np.sin(self.axes)])
        self.body_radius, self.max_range = body_radius, max_range
        self.lane_half_width = body_radius + cfg.margin
        step = math.radians(cfg.step_deg)
        count = math.floor(math.radians(cfg.sector_deg) / step + 1e-9)
        self.candidates = step * np.arange(-count, count + 1)
        self._candidate_directions = np.column_stack(
            [np.cos(self.candidates), np.sin(self.candidates)]
        )

    def obstacle_points(self, ranges: np.ndarray) -> np.ndarray:
        """Robot-frame (x forward, y left) points of the readings that hit something, (n, 2)."""
        ranges = np.asarray(ranges, dtype=float)
        if ranges.shape != self.axes.shape:
            raise ValueError(f"expected {len(self.axes)} sonar ranges, got shape {ranges.shape}")
        hit = ranges < self.max_range
        distance = ranges[hit] + self.body_radius
        return distance[:, None] * self._axis_units[hit]

    def free_distance(self, points: np.ndarray, headings: float | np.ndarray) -> np.ndarray:
        """Distance (m, capped at ``horizon``) the widened robot drives along each heading."""
        headings = np.atleast_1d(np.asarray(headings, dtype=float))
        return self._free(points, np.column_stack([np.cos(headings), np.sin(headings)]))

    def _free(self, points: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """:meth:`free_distance` along unit ``directions`` (headings, 2)."""
        along = directions @ points.T  # (headings, points)
        half_width, horizon = self.lane_half_width, self.cfg.horizon
        return _free_reach(along, directions, points, half_width, half_width**2, horizon)

    def adjust(
        self, ranges: np.ndarray, bearing: float, v: float, w: float, max_yaw_rate: float
    ) -> tuple[float, float]:
        """The command (v, w) after avoidance; ``bearing`` is the follower's target heading."""
        points = self.obstacle_points(ranges)
        if v <= 0:  # turning on the spot sweeps nothing new for a round robot
            return v, w
        if self.free_distance(points, bearing)[0] >= self.cfg.horizon:
            return v, w
        free = self._free(points, self._candidate_directions)
        clear = free >= self.cfg.horizon
        if clear.any():
            options = np.flatnonzero(clear)
            choice = options[np.argmin(np.abs(self.candidates[options] - bearing))]
        else:  # the freest heading; ties go to the one nearest the follower's
            choice = int(np.argmax(free - 1e-6 * np.abs(self.candidates - bearing)))
        heading = float(self.candidates[choice])
        cfg = self.cfg
        ahead = self.free_distance(points, 0.0)[0]
        scale = np.clip((ahead - cfg.stop_distance) / (cfg.slow_distance - cfg.stop_distance), 0, 1)
        return float(v * scale), float(np.clip(cfg.gain * heading, -max_yaw_rate, max_yaw_rate))


@compiled
def _free_reach(
    along: np.ndarray,
    directions: np.ndarray,
    points: np.ndarray,
    half_width: float,
    half_width_squared: float,
    horizon: float,
) -> np.ndarray:
    """Per heading, the nearest reach over the points (``along`` each, from the matrix product):
    a point in the lane (ahead, nearer its centre line than ``half_width``) stops the robot's
    front arc ``along - sqrt(half_width^2 - lateral^2)`` (at least 0) ahead; capped at
    ``horizon``. numpy's elementwise answers (np.maximum, np.where, min with ``initial``,
    np.minimum), NaN kept."""
    free = np.empty(along.shape[0])
    for h in range(along.shape[0]):
        dx, dy = directions[h, 0], directions[h, 1]
        nearest = horizon
        for k in range(points.shape[0]):
            ahead = along[h, k]
            lateral = abs(dx * points[k, 1] - dy * points[k, 0])
            reach = horizon
            if ahead > 0 and lateral < half_width:
                chord = half_width_squared - lateral * lateral
                if not (chord >= 0.0 or chord != chord):
                    chord = 0.0
                reach = ahead - np.sqrt(chord)
                if not (reach >= 0.0 or reach != reach):
                    reach = 0.0
            if not (nearest <= reach or nearest != nearest):
                nearest = reach
        free[h] = nearest if (nearest <= horizon or nearest != nearest) else horizon
    return free
