"""The lens: radial-tangential distortion and vignetting, applied to an undistorted render.

Renderers draw straight lines straight. :class:`Lens` therefore has them draw a pinhole
*render camera* with the true focal length, large enough to hold where every pixel of the
distorted image comes from, and resamples it (``cv2.remap``, bilinear) into the true
``W x H`` image: pixel ``(u, v)`` takes the render's value at ``K_r @ undistort(K^-1 (u, v))``,
so a world point lands where ``cv2.projectPoints`` with the true K and distortion puts it.
Vignetting is a per-pixel gain with the shape of the ``cos^4`` law of the field angle,
scaled so the corner loses ``vignetting`` of its light (:func:`cos4_gain`; the sensor
applies it).
With no distortion the render camera is the camera itself and nothing is resampled. The
resampled image is written into a buffer made once per type (valid until the next call).
"""

from __future__ import annotations

import cv2
import numpy as np

from stsf_gym.envs.sensors.camera import PinholeCamera, projection_from_K

MARGIN_PX = 2  # render pixels beyond the outermost source pixel (bilinear needs a neighbour)


def cos4_gain(camera: PinholeCamera, vignetting: float) -> np.ndarray:
    """Relative illumination (H, W, 1) float32: 1 on the axis, ``1 - vignetting`` at a corner.

    Natural vignetting follows ``cos^4`` of the field angle; its shape is scaled so the
    strength is one number that a user can set from a flat-field picture."""
    u, v = np.meshgrid(np.arange(camera.width), np.arange(camera.height))
    xy = camera.calibration.to_normalised(np.stack([u, v], axis=-1).astype(float))
    falloff = 1 - 1 / (1 + (xy**2).sum(axis=-1)) ** 2  # 1 - cos^4(field angle)
    corner = falloff.max()
    gain = 1 - vignetting * falloff / corner if corner > 0 else np.ones_like(falloff)
    return gain[..., None].astype(np.float32)


class Lens:
    """Maps renders of :attr:`render_K` (``render_size``) to the true camera's image."""

    def __init__(self, camera: PinholeCamera) -> None:
        self.camera = camera
        w, h = camera.width, camera.height
        self.distorted = camera.calibration.distorted
        self._out: dict[np.dtype, np.ndarray] = {}  # the image of each render type
        if not self.distorted:
            self.render_K, self.render_size, self._maps = camera.K, (w, h), None
            return
        u, v = np.meshgrid(np.arange(w, dtype=float), np.arange(h, dtype=float))
        xy = camera.calibration.to_normalised(np.stack([u, v], axis=-1))
        f = camera.focal_px
        low = np.floor(xy.reshape(-1, 2).min(axis=0) * f) - MARGIN_PX
        high = np.ceil(xy.reshape(-1, 2).max(axis=0) * f) + MARGIN_PX
        size = (high - low + 1).astype(int)
        self.render_size = (int(size[0]), int(size[1]))
        self.render_K = np.array([[f, 0.0, -low[0]], [0.0, f, -low[1]], [0.0, 0.0, 1.0]])
        source = (xy * f - low).astype(np.float32)
        self._maps = cv2.convertMaps(source[..., 0], source[..., 1], cv2.CV_16SC2)

    def projection_matrix(self) -> np.ndarray:
        """OpenGL projection of the render camera."""
        cam = self.camera
        return projection_from_K(self.render_K, *self.render_size, cam.near, cam.far)

    def __call__(self, render: np.ndarray) -> np.ndarray:
        """The true camera's image (H, W, C) of a render of the render camera."""
        if self._maps is None:
            return render
        shape = (self.camera.height, self.camera.width, *render.shape[2:])
        out = self._out.get(render.dtype)
        if out is None or out.shape != shape:
            out = self._out[render.dtype] = np.empty(shape, render.dtype)
        return cv2.remap(
            render, *self._maps, cv2.INTER_LINEAR, dst=out, borderMode=cv2.BORDER_REPLICATE
        )
