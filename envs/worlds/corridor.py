"""The corridor world built from a :class:`~stsf_gym.envs.config.WorldConfig`: floor, walls, clutter
and textured landmark boards (the paper's Fig. 3 pattern), described once as scene shapes
(:mod:`stsf_gym.envs.rendering.scene`) that the simulator turns into PyBullet bodies and the camera
draws.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from stsf_gym.envs.config import LandmarkSpec, WorldConfig
from stsf_gym.envs.rendering.scene import Board, Box, Cylinder
from stsf_gym.envs.sensors.camera import PinholeCamera
from stsf_gym.envs.simulator import Simulator
from stsf_gym.geometry import compiled
from stsf_gym.validation import ConfigError
from stsf_gym.vision.landmarks import (
    board_corners,
    landmark_image,
    square_centres,
    square_corners,
)

WALL_RGBA = (0.78, 0.76, 0.72, 1.0)
FLOOR_RGBA = (0.45, 0.42, 0.38, 1.0)
OBSTACLE_RGBA = (0.55, 0.35, 0.2, 1.0)
#: no board's corners (0 boards, 4 corners, 2 pixel coordinates)
NO_CORNERS = np.zeros((0, 4, 2))
NO_CORNERS.setflags(write=False)
RAY_CLEARANCE = 0.1  # m
BOARD_OFFSET = 0.02  # landmark board in front of the wall face (m), clear of depth fighting


@dataclass(frozen=True)
class Landmark:
    """A landmark board in world coordinates (metres).

    ``right`` and ``up`` span the board plane as a viewer facing it sees them; ``normal``
    points out of the wall. Square centres and corners follow
    :func:`stsf_gym.vision.landmarks.square_centres` order.
    """

    id: int
    centre: np.ndarray
    normal: np.ndarray
    right: np.ndarray
    up: np.ndarray
    square_centres: np.ndarray  # (M, 3)
    square_corners: np.ndarray  # (M, 4, 3)
    board_corners: np.ndarray  # (4, 3)

    def to_world(self, plane_xy: np.ndarray) -> np.ndarray:
        """World points of landmark-plane coordinates (..., 2)."""
        return plane_to_world(self.centre, self.right, self.up, plane_xy)


def wall_box(segment, thickness: float, height: float) -> Box:
    """The box of a wall ``[x1, y1, x2, y2]`` (its centre line): ``thickness`` across, ``height``
    tall, reaching half the thickness past each end (so walls meeting at a corner close it)."""
    start, end = np.asarray(segment[:2], dtype=float), np.asarray(segment[2:], dtype=float)
    delta = end - start
    length = float(np.hypot(*delta))
    centre = (start + end) / 2
    half = (length / 2 + thickness / 2, thickness / 2, height / 2)
    return Box((centre[0], centre[1], height / 2), half, math.atan2(delta[1], delta[0]), WALL_RGBA)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


@compiled
def _facing_and_near(
    facing_dots: np.ndarray, centres: np.ndarray, eye: np.ndarray, far: float
) -> np.ndarray:
    """Whether each board faces ``eye`` (``facing_dots``, ``n . (eye - c)``, positive) and lies
    nearer than ``far``: ``np.linalg.norm(c - eye, axis=1) < far``, its sum in its order."""
    shown = np.empty(len(centres), np.bool_)
    for i in range(len(centres)):
        dx, dy, dz = centres[i, 0] - eye[0], centres[i, 1] - eye[1], centres[i, 2] - eye[2]
        shown[i] = facing_dots[i] > 0 and np.sqrt(dx * dx + dy * dy + dz * dz) < far
    return shown


@compiled
def _inside_frame(uv: np.ndarray, right: float, bottom: float) -> np.ndarray:
    """Whether every corner (N, 4, 2) of each board lies within ``[-0.5, right] x [-0.5,
    bottom]`` pixels (a NaN corner is outside)."""
    inside = np.empty(uv.shape[0], np.bool_)
    for i in range(uv.shape[0]):
        inside[i] = True
        for k in range(uv.shape[1]):
            u, v = uv[i, k, 0], uv[i, k, 1]
            if not (u >= -0.5 and v >= -0.5 and u <= right and v <= bottom):
                inside[i] = False
    return inside


def plane_to_world(centre, right, up, plane_xy: np.ndarray) -> np.ndarray:
    """World coordinates of points ``plane_xy`` (..., 2) on the plane through ``centre`` spanned
    by ``right`` and ``up``.
    """
    return centre + plane_xy[..., :1] * right + plane_xy[..., 1:2] * up


def _landmark_frame(world: WorldConfig, spec: LandmarkSpec) -> tuple[np.ndarray, ...]:
    yaw = math.radians(spec.facing_deg)
    normal = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    up = np.array([0.0, 0.0, 1.0])
    right = np.cross(up, normal)
    offset = world.wall_thickness / 2 + BOARD_OFFSET
    centre = np.array([*spec.at, world.landmark_height]) + offset * normal
    return centre, normal, right, up


class CorridorWorld:
    """Static bodies of one world in one simulator, and the landmark geometry."""

    def __init__(self, sim: Simulator, cfg: WorldConfig) -> None:
        self.sim, self.cfg = sim, cfg
        ids = [spec.id for spec in cfg.landmarks]
        if len(set(ids)) != len(ids):
            raise ConfigError(f"world {cfg.name!r}: landmark ids must be unique, got {ids}")
        xy = np.array([p for w in cfg.walls for p in (w[:2], w[2:])] + list(cfg.path))
        self.bounds = np.array(
            [xy.min(axis=0) - 1.0, xy.max(axis=0) + 1.0]
        )  # [[xmin, ymin], [xmax, ymax]]
        self.floor = self._box(
            self.bounds.mean(axis=0), np.ptp(self.bounds, axis=0) / 2, 0.05, -0.05, 0.0, FLOOR_RGBA
        )
        self.walls = [self._wall(seg) for seg in cfg.walls]
        self.obstacles = [self._obstacle(o) for o in cfg.obstacles]
        self.boards: dict[int, int] = {}  # landmark id -> its board's body
        self.landmarks = [self._landmark(spec) for spec in cfg.landmarks]
        # the landmarks' geometry stacked, for the per-frame view tests
        self._normals = np.array([lm.normal for lm in self.landmarks]).reshape(-1, 3)
        self._centres = np.array([lm.centre for lm in self.landmarks]).reshape(-1, 3)
        self._corners = np.array([lm.board_corners for lm in self.landmarks]).reshape(-1, 4, 3)

    def add_board(self, spec: LandmarkSpec) -> int:
        """The body of a new board showing landmark ``spec.id``'s pattern where ``spec`` says
        (a map landmark's, or a decoy's that is not in :attr:`landmarks`)."""
        centre, normal, right, up = _landmark_frame(self.cfg, spec)
        pattern = self.cfg.landmark_pattern
        texture = landmark_image(spec.id, pattern)
        return self.sim.add(Board(centre, right, up, normal, pattern.size, texture))

    def landmarks_in_view(self, camera: PinholeCamera, pose: np.ndarray) -> list[int]:
        """Ids of landmarks wholly inside the frame of ``camera`` at world-from-camera
        ``pose``, facing it, present (a fault may remove one) and not occluded."""
        return self.boards_in_view(camera, pose)[0]

    def boards_in_view(
        self, camera: PinholeCamera, pose: np.ndarray
    ) -> tuple[list[int], np.ndarray]:
        """:meth:`landmarks_in_view`'s ids, and their boards' corners in the image (N, 4, 2) as
        ``camera.project`` gives them (a point's pixels do not depend on the others projected
        with it)."""
        eye = pose[:3, 3]
        facing = np.einsum("ij,ij->i", self._normals, eye - self._centres)
        in_range = _facing_and_near(facing, self._centres, eye, camera.far)
        shown = [
            k
            for k in np.flatnonzero(in_range).tolist()
            if self.board_visible(self.boards[self.landmarks[k].id])
        ]
        if not shown:
            return [], NO_CORNERS
        # every shown board's corners projected at once
        uv = camera.project(pose, self._corners[shown].reshape(-1, 3)).reshape(-1, 4, 2)
        inside = _inside_frame(uv, camera.width - 0.5, camera.height - 0.5)
        rows = [row for row, ok in enumerate(inside.tolist()) if ok]
        if not rows:
            return [], NO_CORNERS
        candidates = [self.landmarks[shown[row]] for row in rows]
        # rays start a little ahead of the optical centre, which sits on the robot's own mast
        starts = [eye + RAY_CLEARANCE * _unit(lm.centre - eye) for lm in candidates]
        hits = self.sim.client.rayTestBatch(
            [p.tolist() for p in starts], [lm.centre.tolist() for lm in candidates]
        )
        clear = [k for k, hit in enumerate(hits) if hit[0] < 0]
        return [candidates[k].id for k in clear], uv[[rows[k] for k in clear]]

    def board_visible(self, body: int) -> bool:
        """Whether the board of body ``body`` is in the world (not removed by a fault)."""
        return body not in self.sim.scene.hidden

    def set_board_visible(self, body: int, visible: bool) -> None:
        """Take a board out of the world or put it back where it was."""
        self.sim.set_visible(body, visible)

    def _box(self, xy, half_xy, half_z: float, z: float, yaw: float, rgba) -> int:
        return self.sim.add(Box((xy[0], xy[1], z), (half_xy[0], half_xy[1], half_z), yaw, rgba))

    def _wall(self, segment) -> int:
        start, end = np.array(segment[:2]), np.array(segment[2:])
        delta = end - start
        length = float(np.hypot(*delta))
        if length <= 0:
            raise ConfigError(
                f"world {self.cfg.name!r}: wall segment {list(segment)} has no length"
            )
        return self.sim.add(wall_box(segment, self.cfg.wall_thickness, self.cfg.wall_height))

    def _obstacle(self, spec) -> int:
        if spec.shape == "box":
            length, width, height = spec.size
            return self._box(
                spec.position,
                (length / 2, width / 2),
                height / 2,
                height / 2,
                math.radians(spec.yaw_deg),
                OBSTACLE_RGBA,
            )
        radius, height = spec.size
        return self.sim.add(Cylinder(tuple(spec.position), radius, height, OBSTACLE_RGBA))

    def _landmark(self, spec: LandmarkSpec) -> Landmark:
        pattern = self.cfg.landmark_pattern
        centre, normal, right, up = _landmark_frame(self.cfg, spec)
        self.boards[spec.id] = self.add_board(spec)
        frame = (centre, right, up)
        return Landmark(
            spec.id,
            centre,
            normal,
            right,
            up,
            plane_to_world(*frame, square_centres(spec.id, pattern)),
            plane_to_world(*frame, square_corners(spec.id, pattern)),
            plane_to_world(*frame, board_corners(pattern)),
        )
