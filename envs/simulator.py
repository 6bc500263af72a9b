"""The PyBullet simulator: one ``BulletClient`` per env, the scene, its renderer, and assets.

Every env owns one :class:`Simulator` and never touches the global ``pybullet`` state, so
many envs live in one process and in vector-env workers. PyBullet's C banners are captured
(:mod:`stsf_gym.envs.quiet`) unless ``STSF_GYM_VERBOSE`` is set.
"""

from __future__ import annotations

import hashlib
import importlib.util
import math
import os
import warnings
from contextlib import nullcontext
from pathlib import Path

import cv2
import numpy as np

from stsf_gym.envs.quiet import quiet_c_output
from stsf_gym.envs.rendering.gl_renderer import GLRenderer, gl_inherited
from stsf_gym.envs.rendering.scene import Board, Box, Scene, Shape
from stsf_gym.validation import ConfigError

with quiet_c_output():  # PyBullet's banners: envs/quiet.py
    import pybullet
    from pybullet_utils.bullet_client import BulletClient


class BoundClient(BulletClient):
    """A ``BulletClient`` that binds each PyBullet function to its server once: the parent's
    ``__getattr__`` builds a new ``functools.partial`` on every access (after an ``inspect``
    test), which the two dozen calls of each step paid for every time."""

    def __getattr__(self, name: str):
        attribute = super().__getattr__(name)
        if name != "disconnect":  # the parent marks the client closed on that access
            self.__dict__[name] = attribute
        return attribute


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
HIDDEN_DEPTH = -50.0  # m: where a body taken out of the world waits, below the floor
BANNER_FRAMES = 2  # the EGL plugin prints a line on each of a client's first two frames


def cache_file(name: str, content: bytes) -> Path:
    """Write ``content`` once to a content-addressed cache file and return its path.

    Assets (URDF, textures) are shared by all envs and processes; writes are atomic.
    """
    root = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "stsf_gym"
    digest = hashlib.sha1(content).hexdigest()[:16]
    path = root / f"{Path(name).stem}-{digest}{Path(name).suffix}"
    if not path.is_file():
        root.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_bytes(content)
        os.replace(tmp, path)
    return path


_egl_loaded_pid: int | None = None  # the process that loaded PyBullet's EGL plugin

RENDERERS = ("auto", "gl", "egl", "tiny", "none")


def egl_inherited() -> bool:
    """True in a process forked after its parent loaded EGL: EGL then deadlocks here."""
    return _egl_loaded_pid is not None and _egl_loaded_pid != os.getpid()


FORK_MESSAGE = (
    "an EGL context was made before this process was forked and would deadlock here; start "
    "workers with 'forkserver' or 'spawn' (e.g. AsyncVectorEnv(..., context='forkserver'))"
)


NOT_COPYABLE = (
    "a stsf-gym env cannot be copied or pickled: it holds a PyBullet physics server, which a "
    "copy would share (stepping the copy would move the original's robot, closing it would "
    "disconnect both). Make another env instead: gym.make(env.spec), reset with the same seed "
    "and options for the same episode"
)


class Simulator:
    """A PyBullet physics client with a fixed time step, the world's scene and its renderer.

    Args:
        physics_hz: physics steps per simulated second.
        renderer: ``"gl"`` (the project's OpenGL renderer of :attr:`scene`,
            :mod:`stsf_gym.envs.rendering.gl_renderer`), ``"egl"`` (PyBullet's EGL plugin),
            ``"tiny"`` (PyBullet's TinyRenderer), ``"auto"`` (the first of gl, egl, tiny that works
            here) or ``"none"`` when nothing is rendered. The choice is in :attr:`renderer`. EGL
            cannot be used in a process forked after its parent made an EGL context (Mesa
            deadlocks): ``"auto"`` then falls back to TinyRenderer with a warning,
            ``"gl"``/``"egl"`` raise; vector envs should use the ``"forkserver"`` or ``"spawn"``
            start method.
    """

    def __init__(self, physics_hz: float, renderer: str = "auto") -> None:
        if renderer not in RENDERERS:
            raise ConfigError(f"camera.renderer must be one of {RENDERERS[:-1]}, got {renderer!r}")
        with quiet_c_output():
            self.client = BoundClient(connection_mode=pybullet.DIRECT)
        self.time_step = 1.0 / physics_hz
        self._set_physics()
        self.scene = Scene()
        self._hidden_from: dict[int, tuple] = {}  # hidden body -> its pose in the world
        self._gl: GLRenderer | None = None
        self._closed = False
        self._frames = 0  # rendered so far: the first ones print EGL banners
        self.renderer = self._choose_renderer(renderer)

    def _set_physics(self) -> None:
        """Time step, gravity, and pyramid friction: Bullet's default friction cone lets
        wheels creep along their contact as their torque reverses (a body turned to and fro on
        the spot drifted 2.3 deg in 30 s on perfect encoders; with pyramid friction 0.02 deg)."""
        self.client.setTimeStep(self.time_step)
        self.client.setGravity(0, 0, -9.81)
        self.client.setPhysicsEngineParameter(enableConeFriction=0)

    def _choose_renderer(self, renderer: str) -> str:
        if renderer in ("tiny", "none"):
            return renderer
        if egl_inherited() or gl_inherited():
            if renderer != "auto":
                raise RuntimeError(FORK_MESSAGE)
            warnings.warn(FORK_MESSAGE + "; using TinyRenderer", RuntimeWarning, stacklevel=3)
            return "tiny"
        errors = []
        for name, load in (("gl", self._load_gl), ("egl", self._load_egl)):
            if renderer in (name, "auto"):
                try:
                    load()
                    return name
                except Exception as err:  # no context here: report it, or try the next
                    errors.append(f"{name}: {err}")
        if renderer != "auto":
            raise RuntimeError(
                f"camera.renderer is {renderer!r} but it cannot start here ({errors[0]}); install "
                "libegl1 libegl-mesa0 libgl1-mesa-dri, or use renderer: auto"
            )
        return "tiny"

    def _load_gl(self) -> None:
        self._gl = GLRenderer(self.scene)

    def _load_egl(self) -> None:
        global _egl_loaded_pid
        spec = importlib.util.find_spec("eglRenderer")
        if spec is None or not spec.origin:
            raise RuntimeError("PyBullet's eglRenderer plugin is not installed")
        with quiet_c_output():
            plugin = self.client.loadPlugin(spec.origin, "_eglRendererPlugin")
        if plugin < 0:
            raise RuntimeError("PyBullet's EGL plugin did not load")
        _egl_loaded_pid = os.getpid()

    def add(self, shape: Shape) -> int:
        """A static PyBullet body for ``shape`` (collision and visual), kept in :attr:`scene`."""
        c = self.client
        if isinstance(shape, Board):
            body = self._add_board(shape)
        else:
            rgba = list(shape.rgba)
            if isinstance(shape, Box):
                collision = c.createCollisionShape(c.GEOM_BOX, halfExtents=list(shape.half))
                visual = c.createVisualShape(
                    c.GEOM_BOX, halfExtents=list(shape.half), rgbaColor=rgba
                )
                position, yaw = list(shape.centre), shape.yaw
            else:
                r, h = shape.radius, shape.height
                collision = c.createCollisionShape(c.GEOM_CYLINDER, radius=r, height=h)
                visual = c.createVisualShape(c.GEOM_CYLINDER, radius=r, length=h, rgbaColor=rgba)
                position, yaw = [*shape.xy, h / 2], 0.0
            body = c.createMultiBody(
                baseMass=0,
                baseCollisionShapeIndex=collision,
                baseVisualShapeIndex=visual,
                basePosition=position,
                baseOrientation=c.getQuaternionFromEuler([0, 0, yaw]),
            )
        self.scene.add(body, shape)
        return body

    def _add_board(self, board: Board) -> int:
        """A textured quad without collision (PyBullet's renderers need an OBJ with UVs)."""
        c = self.client
        image = cv2.cvtColor(board.texture, cv2.COLOR_GRAY2BGR)
        _, png = cv2.imencode(".png", image)
        texture_file = cache_file("board.png", png.tobytes())
        # One OBJ file per texture: PyBullet's EGL renderer shares a texture between all
        # instances of a mesh file, so boards built from one file would all show the same one.
        quad = cache_file("board.obj", f"# {texture_file.name}\n{QUAD_OBJ}".encode())
        visual = c.createVisualShape(
            c.GEOM_MESH, fileName=str(quad), meshScale=[board.size, board.size, 1.0]
        )
        body = c.createMultiBody(
            baseMass=0,
            baseVisualShapeIndex=visual,
            basePosition=board.centre.tolist(),
            baseOrientation=quaternion(board.rotation()),
        )
        texture = c.loadTexture(str(texture_file))
        c.changeVisualShape(body, -1, textureUniqueId=texture, rgbaColor=[1, 1, 1, 1])
        return body

    def set_visible(self, body: int, visible: bool) -> None:
        """Show a scene body or take it out of the world (moved far below the floor)."""
        if visible == (body not in self.scene.hidden):
            return
        c = self.client
        if visible:
            c.resetBasePositionAndOrientation(body, *self._hidden_from.pop(body))
        else:
            self._hidden_from[body] = c.getBasePositionAndOrientation(body)
            c.resetBasePositionAndOrientation(body, [0.0, 0.0, HIDDEN_DEPTH], [0, 0, 0, 1])
        self.scene.set_visible(body, visible)

    def clear(self) -> None:
        """Remove every body and the scene (to build another world), keeping the time step
        and gravity."""
        self.client.resetSimulation()
        self._set_physics()
        self.scene.clear()
        self._hidden_from.clear()

    def step(self, substeps: int) -> None:
        """Advance the physics by ``substeps`` steps."""
        for _ in range(substeps):
            self.client.stepSimulation()

    def render(
        self, width: int, height: int, view: np.ndarray, projection: np.ndarray
    ) -> np.ndarray:
        """The robot camera's RGB uint8 image (height, width, 3) for OpenGL 4x4 view and
        projection matrices, drawn by :attr:`renderer` (``gl`` draws the scene, not the robot)."""
        if self.renderer == "none":
            raise RuntimeError("this simulator was built without a renderer (camera disabled)")
        if self._gl is not None:
            return self._gl.render(width, height, view, projection)
        return self.render_bodies(width, height, view, projection)

    def render_bodies(
        self, width: int, height: int, view: np.ndarray, projection: np.ndarray
    ) -> np.ndarray:
        """Every PyBullet body, the robot's included (a view for people), with PyBullet's own
        renderer: its EGL plugin when loaded, TinyRenderer otherwise."""
        if self.renderer != "egl":  # TinyRenderer draws half a pixel right and up
            shift = np.eye(4)
            shift[:2, 3] = -1.0 / width, -1.0 / height
            projection = shift @ projection
        flag = (
            pybullet.ER_BULLET_HARDWARE_OPENGL
            if self.renderer == "egl"
            else pybullet.ER_TINY_RENDERER
        )
        with quiet_c_output() if self._frames < BANNER_FRAMES else nullcontext():
            _, _, rgba, _, _ = self.client.getCameraImage(
                width,
                height,
                viewMatrix=view.T.ravel().tolist(),
                projectionMatrix=projection.T.ravel().tolist(),
                renderer=flag,
                shadow=0,
                flags=pybullet.ER_NO_SEGMENTATION_MASK,
            )
        self._frames += 1
        return np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)[:, :, :3].copy()

    def __reduce_ex__(self, protocol):
        """Refuse copy, deepcopy and pickle: a copy would hold the same PyBullet server, so
        stepping it would move the original's robot and closing it would disconnect both."""
        raise TypeError(NOT_COPYABLE)

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` has disconnected the simulation."""
        return self._closed

    def close(self) -> None:
        """Disconnect; calling it again is harmless."""
        if not self._closed:
            self._closed = True
            if self._gl is not None:
                self._gl.release()
            with quiet_c_output():
                self.client.disconnect()


def quaternion(rotation: np.ndarray) -> list[float]:
    """Quaternion [x, y, z, w] of a proper rotation matrix."""
    m = rotation
    w = math.sqrt(max(0.0, 1 + m[0, 0] + m[1, 1] + m[2, 2])) / 2
    x = math.copysign(math.sqrt(max(0.0, 1 + m[0, 0] - m[1, 1] - m[2, 2])) / 2, m[2, 1] - m[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1 - m[0, 0] + m[1, 1] - m[2, 2])) / 2, m[0, 2] - m[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1 - m[0, 0] - m[1, 1] + m[2, 2])) / 2, m[1, 0] - m[0, 1])
    return [x, y, z, w]
