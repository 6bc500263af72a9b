"""The PyBullet simulator: one ``BulletClient`` per env, its renderer, and generated assets.

Every env owns one :class:`Simulator` and never touches the global ``pybullet`` state, so
many envs live in one process and in vector-env workers. PyBullet's C banners are captured
(:mod:`envs.quiet`) unless ``STSF_GYM_VERBOSE`` is set.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import warnings
from contextlib import nullcontext
from pathlib import Path

import numpy as np

from envs.quiet import quiet_c_output

with quiet_c_output():  # PyBullet's banners: envs/quiet.py
    import pybullet
    from pybullet_utils.bullet_client import BulletClient

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


def egl_inherited() -> bool:
    """True in a process forked after its parent loaded EGL: EGL then deadlocks here."""
    return _egl_loaded_pid is not None and _egl_loaded_pid != os.getpid()


class Simulator:
    """A PyBullet physics client with a fixed time step and a camera renderer.

    Args:
        physics_hz: physics steps per simulated second.
        renderer: ``"auto"`` (EGL when its plugin loads, else TinyRenderer), ``"egl"``,
            ``"tiny"``, or ``"none"`` when nothing is rendered. The choice is in
            :attr:`renderer`. EGL cannot be used in a process forked after its parent loaded
            it (Mesa deadlocks): ``"auto"`` then falls back to TinyRenderer with a warning;
            vector envs should use the ``"forkserver"`` or ``"spawn"`` start method.
    """

    def __init__(self, physics_hz: float, renderer: str = "auto") -> None:
        if renderer not in ("auto", "egl", "tiny", "none"):
            raise ValueError(f"camera.renderer must be auto, egl or tiny, got {renderer!r}")
        with quiet_c_output():
            self.client = BulletClient(connection_mode=pybullet.DIRECT)
        self.client.setTimeStep(1.0 / physics_hz)
        self.client.setGravity(0, 0, -9.81)
        self.time_step = 1.0 / physics_hz
        self._closed = False
        self._frames = 0  # rendered so far: the first ones print EGL banners
        self.renderer = self._load_renderer(renderer) if renderer in ("auto", "egl") else renderer

    def _load_renderer(self, renderer: str) -> str:
        global _egl_loaded_pid
        if egl_inherited():
            message = (
                "PyBullet's EGL renderer was loaded before this process was forked and would "
                "deadlock here; start workers with 'forkserver' or 'spawn' (e.g. "
                "AsyncVectorEnv(..., context='forkserver'))"
            )
            if renderer == "egl":
                raise RuntimeError(message)
            warnings.warn(message + "; using TinyRenderer", RuntimeWarning, stacklevel=3)
            return "tiny"
        spec = importlib.util.find_spec("eglRenderer")
        plugin = -1
        if spec is not None and spec.origin:
            with quiet_c_output():
                plugin = self.client.loadPlugin(spec.origin, "_eglRendererPlugin")
        if plugin >= 0:
            _egl_loaded_pid = os.getpid()
            return "egl"
        if renderer == "egl":
            raise RuntimeError(
                "camera.renderer is 'egl' but PyBullet's EGL plugin did not load "
                "(install libegl1 libegl-mesa0 libgl1-mesa-dri, or use renderer: auto)"
            )
        return "tiny"

    def step(self, substeps: int) -> None:
        for _ in range(substeps):
            self.client.stepSimulation()

    def render(
        self, width: int, height: int, view: np.ndarray, projection: np.ndarray
    ) -> np.ndarray:
        """RGB uint8 image (height, width, 3) for OpenGL 4x4 view and projection matrices."""
        if self.renderer == "none":
            raise RuntimeError("this simulator was built without a renderer (camera disabled)")
        flag = (
            pybullet.ER_BULLET_HARDWARE_OPENGL
            if self.renderer == "egl"
            else (pybullet.ER_TINY_RENDERER)
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

    def close(self) -> None:
        """Disconnect; calling it again is harmless."""
        if not self._closed:
            self._closed = True
            with quiet_c_output():
                self.client.disconnect()
