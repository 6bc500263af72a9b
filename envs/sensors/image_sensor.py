"""The image sensor: vignetting, exposure/gain variation, photon and read noise, 8 bits.

A rendered frame is the scene's radiance in grey levels. :class:`ImageSensor` multiplies it by
the lens's relative illumination (vignetting) and by a per-frame exposure gain ``1 + g``,
``g ~ N(0, gain_std^2)``, adds noise of variance ``read_noise^2 + shot_noise * I`` (read noise
and photon shot noise, Gaussian at these counts) and rounds to 8 bits.

Drawing a fresh normal deviate for every pixel of every frame costs more than the rest of the
frame's handling, so the sensor draws ``BANK_FRAMES`` frames' worth of standard normal
deviates from the env's generator at each reset and gives each frame the window at a random
offset of that bank: within a frame the noise is independent per pixel and channel.
"""

from __future__ import annotations

import numpy as np

from envs.config import SensorConfig

BANK_FRAMES = 4


class ImageSensor:
    """``sensor(radiance, rng) -> uint8 image`` for frames of ``shape`` (H, W, 3)."""

    def __init__(self, cfg: SensorConfig, shape: tuple[int, ...], gain: np.ndarray) -> None:
        self.cfg, self.shape, self.gain = cfg, shape, gain
        self.size = int(np.prod(shape))
        self.noisy = cfg.read_noise > 0 or cfg.shot_noise > 0
        self.bank = np.zeros(0, np.float32)

    def reset(self, rng: np.random.Generator) -> None:
        if self.noisy:
            self.bank = rng.standard_normal(BANK_FRAMES * self.size, dtype=np.float32)

    def __call__(self, radiance: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        cfg = self.cfg
        exposure = 1.0 + cfg.gain_std * rng.standard_normal() if cfg.gain_std > 0 else 1.0
        signal = radiance.astype(np.float32) * (self.gain * np.float32(exposure))
        if self.noisy:
            offset = int(rng.integers(len(self.bank) - self.size + 1))
            normal = self.bank[offset : offset + self.size].reshape(self.shape)
            if cfg.shot_noise > 0:
                std = np.sqrt(cfg.read_noise**2 + cfg.shot_noise * np.maximum(signal, 0.0))
            else:
                std = np.float32(cfg.read_noise)
            signal += std * normal
        return np.clip(np.rint(signal), 0, 255).astype(np.uint8)
