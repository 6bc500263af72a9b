"""The image sensor: vignetting, exposure/gain variation, photon and read noise, 8 bits.

A rendered frame is the scene's radiance in grey levels. :class:`ImageSensor` multiplies it by
the lens's relative illumination (vignetting) and by a per-frame exposure gain ``1 + g``,
``g ~ N(0, gain_std^2)``, adds noise of variance ``read_noise^2 + shot_noise * I`` (read noise
and photon shot noise, Gaussian at these counts; ``I`` the signal rounded to a grey level for
the variance) and rounds to 8 bits.

Drawing a fresh normal deviate for every pixel of every frame costs more than the rest of the
frame's handling, so the sensor draws ``BANK_FRAMES`` frames' worth of standard normal
deviates from the env's generator at each reset and gives each frame the window at a random
offset of that bank: within a frame the noise is independent per pixel and channel. The
frame's intermediate images and the frame itself live in buffers made once (a fresh 1 MB
array per frame costs its page faults); the frame returned is overwritten by the next.
"""

from __future__ import annotations

import cv2
import numpy as np

from stsf_gym.envs.config import SensorConfig

BANK_FRAMES = 4


class ImageSensor:
    """``sensor(radiance, rng) -> uint8 image`` for frames of ``shape`` (H, W, 3); ``gain`` is
    the lens's relative illumination (H, W, 1)."""

    def __init__(self, cfg: SensorConfig, shape: tuple[int, ...], gain: np.ndarray) -> None:
        self.cfg, self.shape = cfg, shape
        self.gain = np.ascontiguousarray(np.broadcast_to(gain, shape), np.float32)
        self.size = int(np.prod(shape))
        self.noisy = cfg.read_noise > 0 or cfg.shot_noise > 0
        # noise std (grey levels) of each whole grey level of signal
        levels = np.arange(256, dtype=np.float32)
        self.std = np.sqrt(cfg.read_noise**2 + cfg.shot_noise * levels).astype(np.float32)
        self.bank = np.zeros(0, np.float32)
        self._signal = np.empty(shape, np.float32)
        self._levels = np.empty(shape, np.uint8)
        self._noise = np.empty(shape, np.float32)
        self._frame = np.empty(shape, np.uint8)

    def reset(self, rng: np.random.Generator) -> None:
        """Draw this episode's bank of noise from ``rng``."""
        if self.noisy:
            self.bank = rng.standard_normal(BANK_FRAMES * self.size, dtype=np.float32)

    def __call__(self, radiance: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """The 8-bit frame of ``radiance`` (valid until the next call)."""
        cfg = self.cfg
        exposure = 1.0 + cfg.gain_std * rng.standard_normal() if cfg.gain_std > 0 else 1.0
        # OpenCV's arithmetic: one pass each, and saturating, rounding casts to 8 bits
        signal = cv2.multiply(
            radiance, self.gain, dst=self._signal, scale=exposure, dtype=cv2.CV_32F
        )
        if not self.noisy:
            return cv2.add(signal, 0.0, dst=self._frame, dtype=cv2.CV_8U)
        offset = int(rng.integers(len(self.bank) - self.size + 1))
        normal = self.bank[offset : offset + self.size].reshape(self.shape)
        levels = cv2.convertScaleAbs(signal, dst=self._levels)  # signal >= 0: abs changes nothing
        noise = cv2.multiply(cv2.LUT(levels, self.std, dst=self._noise), normal, dst=self._noise)
        return cv2.add(signal, noise, dst=self._frame, dtype=cv2.CV_8U)
