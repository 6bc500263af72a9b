"""The rendered camera: frames drawn by the simulator's renderer through the lens and sensor.

A frame is exposed for ``sensor.exposure_s`` centred on its time stamp. When the camera's
motion during that time (the robot's and the pan/tilt mount's, from PyBullet's link
velocities) moves the image by more than ``SUBFRAME_PX``, the frame is the mean of renders at
poses spread over the exposure (motion blur); otherwise one render. Then the lens
(:mod:`stsf_gym.envs.sensors.lens`: distortion, vignetting's gain) and its defocus, and the sensor
(:mod:`stsf_gym.envs.sensors.image_sensor`: exposure gain, noise, 8 bits).
"""

from __future__ import annotations

import cv2
import numpy as np
from gymnasium import spaces

from stsf_gym.envs.config import CameraConfig
from stsf_gym.envs.sensors.camera import PinholeCamera, view_matrix
from stsf_gym.envs.sensors.image_sensor import ImageSensor
from stsf_gym.envs.sensors.lens import Lens, cos4_gain

SUBFRAME_PX = 1.0  # image motion (px) per render of a motion-blurred frame
MAX_SUBFRAMES = 6
NEAR_DEPTH = 2.0  # m: the depth at which translation's image motion is judged


def exposure_poses(
    pose: np.ndarray,
    linear: np.ndarray,
    angular: np.ndarray,
    exposure_s: float,
    focal_px: float,
) -> list[np.ndarray]:
    """World-from-camera poses spread over an exposure centred on ``pose``, the camera moving
    at world ``linear`` (m/s) and ``angular`` (rad/s) velocity; one pose if it hardly moves."""
    speed = np.linalg.norm(angular) + np.linalg.norm(linear) / NEAR_DEPTH
    count = int(np.clip(np.ceil(focal_px * exposure_s * speed / SUBFRAME_PX), 1, MAX_SUBFRAMES))
    if count == 1:
        return [pose]
    poses = []
    for t in ((np.arange(count) + 0.5) / count - 0.5) * exposure_s:
        moved = pose.copy()
        moved[:3, :3] = cv2.Rodrigues(np.asarray(angular, float) * t)[0] @ pose[:3, :3]
        moved[:3, 3] += np.asarray(linear, float) * t
        poses.append(moved)
    return poses


class RenderedCamera:
    """Observation ``image``: ``Box(0, 255, (H, W, 3), uint8)``, the latest frame."""

    def __init__(self, cfg: CameraConfig, camera: PinholeCamera, sim, robot) -> None:
        self.cfg, self.camera, self.sim, self.robot = cfg, camera, sim, robot
        self.lens = Lens(camera)
        self.projection = self.lens.projection_matrix()
        shape = (camera.height, camera.width, 3)
        self.sensor = ImageSensor(cfg.sensor, shape, cos4_gain(camera, cfg.lens.vignetting))
        self.blank = np.zeros(shape, np.uint8)
        self.frame = self.blank
        # made once: a blurred frame's sum of renders, the defocused image of each type
        self._exposure = np.zeros((*self.lens.render_size[::-1], 3), np.float32)
        self._defocused: dict[np.dtype, np.ndarray] = {}

    def observation_space(self) -> dict[str, spaces.Space]:
        """The observation keys this camera adds: ``image``."""
        return {"image": spaces.Box(0, 255, self.blank.shape, np.uint8)}

    def reset(self, rng: np.random.Generator) -> None:
        """Start an episode: the sensor's noise from ``rng``, a blank frame."""
        self.sensor.reset(rng)
        self.frame = self.blank

    def radiance(self, pose: np.ndarray) -> np.ndarray:
        """The frame before the sensor: renders over the exposure, through the lens."""
        linear, angular = self.robot.camera_velocity()
        poses = exposure_poses(
            pose, linear, angular, self.cfg.sensor.exposure_s, self.camera.focal_px
        )
        size = self.lens.render_size
        render = self.sim.render(*size, view_matrix(poses[0]), self.projection)
        if len(poses) > 1:  # the exposure's mean, summed in place
            total = self._exposure
            total.fill(0.0)
            cv2.accumulate(render, total)
            for p in poses[1:]:
                cv2.accumulate(self.sim.render(*size, view_matrix(p), self.projection), total)
            render = np.multiply(total, 1 / len(poses), out=total)
        image = self.lens(render)
        if self.cfg.lens.defocus_px > 0:
            out = self._defocused.setdefault(image.dtype, np.empty_like(image))
            image = cv2.GaussianBlur(image, (0, 0), self.cfg.lens.defocus_px, dst=out)
        return image

    def capture(self, pose: np.ndarray, rng: np.random.Generator) -> None:
        """Expose a frame from the camera's world pose ``pose`` (4x4): render, lens and sensor."""
        self.frame = self.sensor(self.radiance(pose), rng)

    def observe(self) -> dict[str, np.ndarray]:
        """The last frame's observation keys."""
        return {"image": self.frame.copy()}
