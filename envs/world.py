"""The corridor world built from a :class:`~envs.config.WorldConfig`: floor, walls, clutter and
textured landmark boards (the paper's Fig. 3 pattern as UV-mapped quads, drawn by both
TinyRenderer and the EGL renderer).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from envs.config import LandmarkSpec, WorldConfig
from envs.simulator import Simulator, cache_file
from stsf_gym.vision.landmarks import (
    LandmarkPattern,
    board_corners,
    landmark_image,
    square_centres,
    square_corners,
)

# A unit square in the x-y plane facing +z, texture coordinates spanning the whole image.
QUAD_OBJ = """v -0.5 -0.5 0
v 0.5 -0.5 0
v 0.5 0.5 0
v -0.5 0.5 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 1
f 1/1/1 2/2/1 3/3/1
f 1/1/1 3/3/1 4/4/1
"""
WALL_RGBA = (0.78, 0.76, 0.72, 1.0)
FLOOR_RGBA = (0.45, 0.42, 0.38, 1.0)
OBSTACLE_RGBA = (0.55, 0.35, 0.2, 1.0)
BOARD_OFFSET = 0.02  # landmark board in front of the wall face (m), clear of depth fighting
HIDDEN_DEPTH = -50.0  # m: where a board taken out of the world waits, below the floor


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


def plane_to_world(centre, right, up, plane_xy: np.ndarray) -> np.ndarray:
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
        self._bodies: list[int] = []  # every body this world made, for remove()
        ids = [spec.id for spec in cfg.landmarks]
        if len(set(ids)) != len(ids):
            raise ValueError(f"world {cfg.name!r}: landmark ids must be unique, got {ids}")
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
        self._hidden: dict[int, tuple] = {}  # body -> its pose while moved out of the world
        self.landmarks = [self._landmark(spec) for spec in cfg.landmarks]

    def add_board(self, spec: LandmarkSpec) -> int:
        """The body of a new board showing landmark ``spec.id``'s pattern where ``spec`` says
        (a map landmark's, or a decoy's that is not in :attr:`landmarks`)."""
        centre, normal, right, up = _landmark_frame(self.cfg, spec)
        c = self.sim.client
        pattern = self.cfg.landmark_pattern
        # One OBJ file per landmark: the EGL renderer shares a texture between all instances
        # of a mesh file, so boards built from one file would all show the same id.
        quad = cache_file(f"landmark{spec.id}.obj", f"# landmark {spec.id}\n{QUAD_OBJ}".encode())
        size = pattern.size
        visual = c.createVisualShape(c.GEOM_MESH, fileName=str(quad), meshScale=[size, size, 1.0])
        body = c.createMultiBody(
            baseMass=0,
            baseVisualShapeIndex=visual,
            basePosition=centre.tolist(),
            baseOrientation=_quaternion(np.column_stack([right, up, normal])),
        )
        self._made(body)
        texture = c.loadTexture(str(_texture_file(spec.id, pattern)))
        c.changeVisualShape(body, -1, textureUniqueId=texture, rgbaColor=[1, 1, 1, 1])
        return body

    def remove(self) -> None:
        """Take every body of this world (floor, walls, clutter, boards) out of the simulator."""
        for body in self._bodies:
            self.sim.client.removeBody(body)
        self._bodies.clear()
        self.boards.clear()
        self._hidden.clear()

    def board_visible(self, body: int) -> bool:
        return body not in self._hidden

    def set_board_visible(self, body: int, visible: bool) -> None:
        """Take a board out of the world (far below the floor) or put it back where it was."""
        c = self.sim.client
        if not visible and body not in self._hidden:
            self._hidden[body] = c.getBasePositionAndOrientation(body)
            c.resetBasePositionAndOrientation(body, [0.0, 0.0, HIDDEN_DEPTH], [0, 0, 0, 1])
        elif visible and body in self._hidden:
            c.resetBasePositionAndOrientation(body, *self._hidden.pop(body))

    def _box(self, xy, half_xy, half_z: float, z: float, yaw: float, rgba) -> int:
        c = self.sim.client
        half = [half_xy[0], half_xy[1], half_z]
        body = c.createMultiBody(
            baseMass=0,
            baseCollisionShapeIndex=c.createCollisionShape(c.GEOM_BOX, halfExtents=half),
            baseVisualShapeIndex=c.createVisualShape(c.GEOM_BOX, halfExtents=half, rgbaColor=rgba),
            basePosition=[xy[0], xy[1], z],
            baseOrientation=c.getQuaternionFromEuler([0, 0, yaw]),
        )
        return self._made(body)

    def _made(self, body: int) -> int:
        self._bodies.append(body)
        return body

    def _wall(self, segment) -> int:
        start, end = np.array(segment[:2]), np.array(segment[2:])
        delta = end - start
        length = float(np.hypot(*delta))
        if length <= 0:
            raise ValueError(f"world {self.cfg.name!r}: wall segment {list(segment)} has no length")
        t, h = self.cfg.wall_thickness, self.cfg.wall_height
        half = (length / 2 + t / 2, t / 2)
        return self._box(
            (start + end) / 2, half, h / 2, h / 2, math.atan2(delta[1], delta[0]), WALL_RGBA
        )

    def _obstacle(self, spec) -> int:
        c = self.sim.client
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
        body = c.createMultiBody(
            baseMass=0,
            baseCollisionShapeIndex=c.createCollisionShape(
                c.GEOM_CYLINDER, radius=radius, height=height
            ),
            baseVisualShapeIndex=c.createVisualShape(
                c.GEOM_CYLINDER, radius=radius, length=height, rgbaColor=OBSTACLE_RGBA
            ),
            basePosition=[*spec.position, height / 2],
        )
        return self._made(body)

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


@functools.lru_cache(maxsize=1024)
def _texture_file(landmark_id: int, pattern: LandmarkPattern) -> Path:
    """The PNG of a landmark's pattern, drawn once per process (worlds are rebuilt often)."""
    grey = landmark_image(landmark_id, pattern)
    _, png = cv2.imencode(".png", cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR))
    return cache_file(f"landmark{landmark_id}.png", png.tobytes())


def _quaternion(rotation: np.ndarray) -> list[float]:
    """Quaternion [x, y, z, w] of a proper rotation matrix."""
    m = rotation
    w = math.sqrt(max(0.0, 1 + m[0, 0] + m[1, 1] + m[2, 2])) / 2
    x = math.copysign(math.sqrt(max(0.0, 1 + m[0, 0] - m[1, 1] - m[2, 2])) / 2, m[2, 1] - m[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1 - m[0, 0] + m[1, 1] - m[2, 2])) / 2, m[0, 2] - m[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1 - m[0, 0] - m[1, 1] + m[2, 2])) / 2, m[1, 0] - m[0, 1])
    return [x, y, z, w]
