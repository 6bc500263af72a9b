"""The top-down map people watch (``render.view: map``), drawn in 2-D with OpenCV.

The map shows the walls, clutter, landmarks, the path and its goal (drawn once), and per
frame the sonar cones with their ranges, the camera's field of view, the landmarks in the
current frame, the true pose, the :data:`MapMarks` the env's map sources give at that frame
(each pose estimate with its 2-sigma ellipse and heading spread, the landmarks the camera is
kept on ringed) and an inset of the current camera frame (or, in the fast sensor mode, of its
detections).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from itertools import cycle

import cv2
import numpy as np

from stsf_gym.envs.config import WorldConfig
from stsf_gym.envs.worlds.corridor import Landmark

BACKGROUND = (236, 236, 232)
WALL, CLUTTER, PATH, GOAL = (70, 70, 70), (150, 110, 80), (120, 160, 220), (60, 170, 90)
TRUTH, FOV, SONAR, IN_VIEW = (20, 20, 20), (250, 200, 40), (220, 80, 80), (255, 140, 0)
ESTIMATE_COLOURS = ((30, 90, 230), (200, 40, 160), (0, 150, 150), (120, 60, 200))
MARGIN_PX = 12
FOV_RANGE_M = 5.0  # how far the field-of-view wedge reaches
INSET_FRACTION = 0.3  # the camera inset's width, as a fraction of the map's
SIGMAS = 2.0


@dataclass
class Estimate:
    """A pose estimate to draw: mean ``[x, y, yaw]`` and 3x3 covariance."""

    mean: np.ndarray
    cov: np.ndarray


#: What one map source (a wrapper, asked at every frame) has the map draw: its pose estimates,
#: ``{label: (mean, cov)}``, and the ids of the landmarks it keeps the camera on (ringed).
MapMarks = tuple[Mapping[str, tuple[np.ndarray, np.ndarray]], Iterable[int]]


class MapView:
    """Draws the top-down map of one world at ``width`` x ``height`` pixels (RGB).

    Args:
        world: the world config (walls, path, obstacles).
        landmarks: the world's landmark boards.
        body_radius: the robot's radius (m).
        sonar_axes: transducer headings in the robot frame (rad); ``sonar_half_width``
            half a cone (rad).
        hfov: the camera's horizontal field of view (rad).
    """

    def __init__(
        self,
        world: WorldConfig,
        landmarks: list[Landmark],
        body_radius: float,
        sonar_axes: np.ndarray,
        sonar_half_width: float,
        hfov: float,
        width: int,
        height: int,
    ) -> None:
        self.size = (width, height)
        self.body_radius, self.hfov = body_radius, hfov
        self.sonar_axes, self.sonar_half_width = np.asarray(sonar_axes), sonar_half_width
        self.landmarks = {lm.id: lm for lm in landmarks}
        ends = np.array([p for wall in world.walls for p in (wall[:2], wall[2:])])
        low, high = ends.min(axis=0), ends.max(axis=0)
        span = np.maximum(high - low, 1e-6)
        self.scale = min((width - 2 * MARGIN_PX) / span[0], (height - 2 * MARGIN_PX) / span[1])
        used = span * self.scale
        self._origin = low - (np.array([width, height]) - used) / 2 / self.scale
        self._base = self._draw_base(world)
        self._inset_corner = self._emptiest_corner()

    # --- drawing ------------------------------------------------------------------------
    def px(self, xy) -> np.ndarray:
        """Pixel coordinates (int32, ..., 2) of world points ``xy`` (..., 2), north up."""
        xy = np.asarray(xy, float)
        u = (xy[..., 0] - self._origin[0]) * self.scale
        v = self.size[1] - (xy[..., 1] - self._origin[1]) * self.scale
        return np.round(np.stack([u, v], axis=-1)).astype(np.int32)

    def draw(
        self,
        pose: np.ndarray,
        camera_pose: np.ndarray,
        sonar: np.ndarray | None,
        in_view: list[int],
        inset: np.ndarray | None,
        caption: str = "",
        marks: Iterable[MapMarks] = (),
    ) -> np.ndarray:
        """The frame: the base map with the robot's sensors, true pose, ``marks`` (one per map
        source, in order; a later source's estimate replaces an earlier one's of its label),
        inset."""
        estimates: dict[str, Estimate] = {}
        targets: set[int] = set()
        for shown, ringed in marks:
            estimates.update(
                {
                    k: Estimate(np.asarray(m, float), np.asarray(c, float))
                    for k, (m, c) in shown.items()
                }
            )
            targets.update(ringed)
        image = self._base.copy()
        shade = image.copy()
        if sonar is not None:
            self._draw_sonar(shade, pose, sonar)
        self._draw_fov(shade, camera_pose)
        cv2.addWeighted(shade, 0.45, image, 0.55, 0.0, dst=image)
        for lm_id in in_view:
            self._mark_landmark(image, lm_id, IN_VIEW, 3)
        for lm_id in targets:
            centre = self.px(self.landmarks[lm_id].centre[:2])
            cv2.circle(image, tuple(centre.tolist()), 9, IN_VIEW, 2, cv2.LINE_AA)
        self._draw_robot(image, pose)
        legend = [("truth", TRUTH)]
        for (label, estimate), colour in zip(estimates.items(), cycle(ESTIMATE_COLOURS)):
            self._draw_estimate(image, estimate, colour)
            legend.append((f"{label} +-{SIGMAS:g} sigma", colour))
        if inset is not None:
            self._draw_inset(image, inset)
        self._draw_legend(image, legend, caption)
        return image

    def _draw_base(self, world: WorldConfig) -> np.ndarray:
        width, height = self.size
        image = np.full((height, width, 3), BACKGROUND, np.uint8)
        path = self.px(world.path)
        cv2.polylines(image, [path], False, PATH, 2, cv2.LINE_AA)
        goal = tuple(path[-1].tolist())
        cv2.circle(image, goal, max(2, round(world.goal_radius * self.scale)), GOAL, 2, cv2.LINE_AA)
        for obstacle in world.obstacles:
            self._draw_obstacle(image, obstacle)
        thickness = max(2, round(world.wall_thickness * self.scale))
        for wall in world.walls:
            a, b = self.px(wall[:2]), self.px(wall[2:])
            cv2.line(image, tuple(a.tolist()), tuple(b.tolist()), WALL, thickness, cv2.LINE_AA)
        for lm_id, landmark in self.landmarks.items():
            self._mark_landmark(image, lm_id, (0, 0, 0), 2)
            label = self.px(landmark.centre[:2] - 0.35 * landmark.normal[:2])  # behind the wall
            cv2.putText(
                image, str(lm_id), tuple((label - (4, -4)).tolist()),
                cv2.FONT_HERSHEY_SIMPLEX, 0.35, (0, 0, 0), 1, cv2.LINE_AA,
            )  # fmt: skip
        return image

    def _draw_obstacle(self, image: np.ndarray, obstacle) -> None:
        centre = np.asarray(obstacle.position, float)
        if obstacle.shape == "cylinder":
            radius = max(1, round(obstacle.size[0] * self.scale))
            cv2.circle(image, tuple(self.px(centre).tolist()), radius, CLUTTER, -1, cv2.LINE_AA)
            return
        yaw = math.radians(obstacle.yaw_deg)
        rotation = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
        half = np.asarray(obstacle.size[:2], float) / 2
        corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * half
        cv2.fillPoly(image, [self.px(centre + corners @ rotation.T)], CLUTTER, cv2.LINE_AA)

    def _mark_landmark(self, image: np.ndarray, lm_id: int, colour, thickness: int) -> None:
        corners = self.landmarks[lm_id].board_corners[:, :2]
        a, b = self.px(corners.min(axis=0)), self.px(corners.max(axis=0))
        cv2.rectangle(image, tuple(a.tolist()), tuple(b.tolist()), colour, thickness)

    def _wedge(self, origin, heading: float, half: float, reach: float) -> np.ndarray:
        angles = heading + np.linspace(-half, half, 9)
        arc = origin + reach * np.column_stack([np.cos(angles), np.sin(angles)])
        return self.px(np.vstack([origin, arc]))

    def _draw_sonar(self, image: np.ndarray, pose: np.ndarray, ranges: np.ndarray) -> None:
        for axis, reach in zip(self.sonar_axes, ranges, strict=True):
            heading = pose[2] + axis
            origin = pose[:2] + self.body_radius * np.array([math.cos(heading), math.sin(heading)])
            wedge = self._wedge(origin, heading, self.sonar_half_width, float(reach))
            cv2.fillPoly(image, [wedge], SONAR, cv2.LINE_AA)

    def _draw_fov(self, image: np.ndarray, camera_pose: np.ndarray) -> None:
        forward = camera_pose[:3, 2]  # the optical axis (OpenCV z)
        if np.hypot(*forward[:2]) < 1e-6:
            return
        heading = math.atan2(forward[1], forward[0])
        wedge = self._wedge(camera_pose[:2, 3], heading, self.hfov / 2, FOV_RANGE_M)
        cv2.fillPoly(image, [wedge], FOV, cv2.LINE_AA)

    def _draw_robot(self, image: np.ndarray, pose: np.ndarray) -> None:
        centre = tuple(self.px(pose[:2]).tolist())
        radius = max(3, round(self.body_radius * self.scale))
        cv2.circle(image, centre, radius, TRUTH, 2, cv2.LINE_AA)
        nose = pose[:2] + self.body_radius * np.array([math.cos(pose[2]), math.sin(pose[2])])
        cv2.line(image, centre, tuple(self.px(nose).tolist()), TRUTH, 2, cv2.LINE_AA)

    def _draw_estimate(self, image: np.ndarray, estimate: Estimate, colour) -> None:
        mean, cov = estimate.mean, estimate.cov
        centre = tuple(self.px(mean[:2]).tolist())
        values, vectors = np.linalg.eigh(0.5 * (cov[:2, :2] + cov[:2, :2].T))
        axes = SIGMAS * np.sqrt(np.clip(values, 0.0, None)) * self.scale
        angle = -math.degrees(math.atan2(vectors[1, 1], vectors[0, 1]))  # image y points down
        half_axes = (max(1, round(axes[1])), max(1, round(axes[0])))
        cv2.ellipse(image, centre, half_axes, angle, 0, 360, colour, 2, cv2.LINE_AA)
        cv2.drawMarker(image, centre, colour, cv2.MARKER_CROSS, 10, 2, cv2.LINE_AA)
        spread = SIGMAS * math.sqrt(max(float(cov[2, 2]), 0.0))
        reach = 1.8 * self.body_radius
        for offset, width in ((0.0, 2), (-spread, 1), (spread, 1)):
            tip = mean[:2] + reach * np.array(
                [math.cos(mean[2] + offset), math.sin(mean[2] + offset)]
            )
            cv2.line(image, centre, tuple(self.px(tip).tolist()), colour, width, cv2.LINE_AA)

    def _emptiest_corner(self) -> str:
        w = round(self.size[0] * INSET_FRACTION)
        h = round(w * 0.75)  # a 4:3 camera frame
        regions = {
            "top-left": self._base[:h, :w], "top-right": self._base[:h, -w:],
            "bottom-left": self._base[-h:, :w], "bottom-right": self._base[-h:, -w:],
        }  # fmt: skip
        return min(regions, key=lambda k: int(np.any(regions[k] != BACKGROUND, axis=2).sum()))

    def _draw_inset(self, image: np.ndarray, frame: np.ndarray) -> None:
        width, height = self.size
        w = round(width * INSET_FRACTION)
        h = round(w * frame.shape[0] / frame.shape[1])
        small = cv2.resize(frame, (w, h), interpolation=cv2.INTER_AREA)
        top = 4 if self._inset_corner.startswith("top") else height - h - 4
        left = 4 if self._inset_corner.endswith("left") else width - w - 4
        image[top : top + h, left : left + w] = small
        cv2.rectangle(image, (left - 1, top - 1), (left + w, top + h), TRUTH, 1)

    def _draw_legend(self, image: np.ndarray, legend, caption: str) -> None:
        """The legend beside the inset's corner (the emptiest part of the map)."""
        lines = [*legend, (caption, TRUTH)]
        inset_h = round(round(self.size[0] * INSET_FRACTION) * 0.75)
        top = self._inset_corner.startswith("top")
        y = inset_h + 22 if top else image.shape[0] - inset_h - 14 * len(lines) - 4
        left = self._inset_corner.endswith("left")
        x = 8 if left else image.shape[1] - round(self.size[0] * INSET_FRACTION) - 4
        for text, colour in lines:
            cv2.putText(image, text, (x, y), cv2.FONT_HERSHEY_SIMPLEX, 0.4, colour, 1, cv2.LINE_AA)
            y += 14


def detections_frame(ids: np.ndarray, points: np.ndarray, width: int, height: int) -> np.ndarray:
    """A black camera-sized frame with the fast sensor mode's detected square centres."""
    frame = np.zeros((height, width, 3), np.uint8)
    for slot in np.flatnonzero(np.asarray(ids) >= 0):
        for u, v in np.asarray(points).reshape(len(ids), -1, 2)[slot]:
            cv2.circle(frame, (round(float(u)), round(float(v))), 2, (255, 255, 255), -1)
    return frame
