"""The world's scene description: the one list of shapes that both PyBullet and the camera use.

The world builder (:mod:`stsf_gym.envs.worlds.corridor`) describes every static thing once, as a
:class:`Box`, a :class:`Cylinder` or a textured :class:`Board`.
:meth:`stsf_gym.envs.simulator.Simulator.add` turns each into a PyBullet body (collision for
contacts and sonar rays, a visual shape for PyBullet's own renderers) and keeps it in the
:class:`Scene`, which the OpenGL camera renderer (:mod:`stsf_gym.envs.rendering.gl_renderer`) draws
as triangles. Nothing here imports PyBullet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

CYLINDER_SIDES = 24
_SQUARE = ((-1, -1), (1, -1), (1, 1), (-1, 1))  # quad corners, counter-clockwise


@dataclass(frozen=True)
class Box:
    """A box of half extents ``half`` (m) centred at ``centre``, turned by ``yaw`` (rad)."""

    centre: tuple[float, float, float]
    half: tuple[float, float, float]
    yaw: float
    rgba: tuple[float, float, float, float]


@dataclass(frozen=True)
class Cylinder:
    """An upright cylinder standing on the floor at ``xy``."""

    xy: tuple[float, float]
    radius: float
    height: float
    rgba: tuple[float, float, float, float]


@dataclass(frozen=True, eq=False)
class Board:
    """A square board of side ``size`` (m) showing ``texture`` (grey, rows top-down) to a viewer
    on its ``normal`` side; ``right`` and ``up`` span it as that viewer sees them."""

    centre: np.ndarray
    right: np.ndarray
    up: np.ndarray
    normal: np.ndarray
    size: float
    texture: np.ndarray

    def rotation(self) -> np.ndarray:
        """World-from-board rotation (columns right, up, normal)."""
        return np.column_stack([self.right, self.up, self.normal])


Shape = Box | Cylinder | Board


#: Floats per vertex of :meth:`Scene.triangles`: position (3), normal (3), uv (2), rgb (3) and
#: layer (1), the board texture's index in :attr:`Scene.textures` (-1 for a plain colour).
VERTEX_FLOATS = 12


def _faces(corners: np.ndarray, normal: np.ndarray, rgb, layer: float) -> np.ndarray:
    """Two triangles of a quad given counter-clockwise (seen from ``normal``), with UVs."""
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    rows = [[*corners[i], *normal, *uv[i], *rgb, layer] for i in (0, 1, 2, 0, 2, 3)]
    return np.asarray(rows, np.float32)


def _rot_z(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def box_triangles(box: Box) -> np.ndarray:
    """The triangles of ``box``'s faces (with normals), for the renderer."""
    rotation = _rot_z(box.yaw)
    half = np.asarray(box.half, float)
    quads = []
    for axis in range(3):
        for sign in (1.0, -1.0):
            n = np.zeros(3)
            n[axis] = sign
            u = np.zeros(3)
            u[(axis + 1) % 3] = 1.0
            v = np.cross(n, u)
            corners = [n * half + a * u * half + b * v * half for a, b in _SQUARE]
            world = np.asarray(corners) @ rotation.T + np.asarray(box.centre)
            quads.append(_faces(world, rotation @ n, box.rgba[:3], -1.0))
    return np.concatenate(quads)


def cylinder_triangles(cylinder: Cylinder) -> np.ndarray:
    """The triangles of ``cylinder``'s side and top (with normals), for the renderer."""
    x, y = cylinder.xy
    r, h = cylinder.radius, cylinder.height
    quads = []
    for k in range(CYLINDER_SIDES):
        a0, a1 = (2 * math.pi * k / CYLINDER_SIDES, 2 * math.pi * (k + 1) / CYLINDER_SIDES)
        p0 = np.array([x + r * math.cos(a0), y + r * math.sin(a0)])
        p1 = np.array([x + r * math.cos(a1), y + r * math.sin(a1)])
        mid = (a0 + a1) / 2
        normal = np.array([math.cos(mid), math.sin(mid), 0.0])
        corners = np.array([[*p0, 0.0], [*p1, 0.0], [*p1, h], [*p0, h]])
        quads.append(_faces(corners, normal, cylinder.rgba[:3], -1.0))
        top = np.array([[x, y, h], [x, y, h], [*p0, h], [*p1, h]])
        quads.append(_faces(top, np.array([0.0, 0.0, 1.0]), cylinder.rgba[:3], -1.0))
    return np.concatenate(quads)


def board_triangles(board: Board, layer: int) -> np.ndarray:
    """The two textured triangles of ``board``, on texture layer ``layer``."""
    half = board.size / 2
    corners = [board.centre + half * (a * board.right + b * board.up) for a, b in _SQUARE]
    return _faces(np.asarray(corners), board.normal, (1.0, 1.0, 1.0), float(layer))


class Scene:
    """The static shapes of one world, each tied to its PyBullet body and shown or hidden.

    :attr:`version` changes whenever what is shown changes (a board added, hidden or shown
    again by a fault), so a renderer uploads the geometry again only then.
    """

    def __init__(self) -> None:
        self.shapes: dict[int, Shape] = {}  # body -> shape
        self.hidden: set[int] = set()
        self.textures: list[np.ndarray] = []
        self._layers: dict[int, int] = {}  # board body -> texture layer
        self.version = 0

    def add(self, body: int, shape: Shape) -> None:
        """Add the shape of PyBullet body ``body``."""
        self.shapes[body] = shape
        if isinstance(shape, Board):
            self._layers[body] = len(self.textures)
            self.textures.append(shape.texture)
        self.version += 1

    def clear(self) -> None:
        """Forget every shape (the simulation was emptied for another world)."""
        self.shapes.clear()
        self.hidden.clear()
        self.textures.clear()
        self._layers.clear()
        self.version += 1

    def set_visible(self, body: int, visible: bool) -> None:
        """Show or hide ``body`` (a fault removing or occluding a board)."""
        if visible == (body not in self.hidden):
            return
        (self.hidden.discard if visible else self.hidden.add)(body)
        self.version += 1

    def triangles(self) -> tuple[np.ndarray, np.ndarray]:
        """Vertex arrays (N, :data:`VERTEX_FLOATS`) of the shown plain shapes and boards."""
        plain = [np.zeros((0, VERTEX_FLOATS), np.float32)]
        boards = list(plain)
        for body, shape in self.shapes.items():
            if body in self.hidden:
                continue
            if isinstance(shape, Box):
                plain.append(box_triangles(shape))
            elif isinstance(shape, Cylinder):
                plain.append(cylinder_triangles(shape))
            else:
                boards.append(board_triangles(shape, self._layers[body]))
        return np.concatenate(plain), np.concatenate(boards)
