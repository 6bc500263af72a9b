"""The camera's Gaussian intensity noise, cut from a bank drawn once per episode.

Drawing a fresh normal deviate for every pixel of every frame costs more than the rest of the
frame's handling in the env, so :class:`ImageNoise` draws ``BANK_FRAMES`` frames' worth of
noise from the env's generator at each reset and gives each frame the window at a random
offset of that bank. Within a frame the noise is independent Gaussian per pixel and channel;
it is rounded to whole grey levels, which changes nothing since the rendered values are whole
(``round(I + n) = I + round(n)``), and the sum is clipped to [0, 255].
"""

from __future__ import annotations

import numpy as np

BANK_FRAMES = 4


class ImageNoise:
    """``noise(image, rng)``: ``image`` plus N(0, ``sigma``^2) grey levels, clipped."""

    def __init__(self, sigma: float, shape: tuple[int, ...]) -> None:
        self.sigma, self.shape = sigma, shape
        self.size = int(np.prod(shape))
        self.bank = np.zeros(0, np.int16)

    def reset(self, rng: np.random.Generator) -> None:
        if self.sigma > 0:
            draws = rng.standard_normal(BANK_FRAMES * self.size, dtype=np.float32) * self.sigma
            self.bank = np.rint(draws).astype(np.int16)

    def __call__(self, image: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        if self.sigma <= 0:
            return image
        offset = int(rng.integers(len(self.bank) - self.size + 1))
        noisy = image.astype(np.int16)
        noisy += self.bank[offset : offset + self.size].reshape(self.shape)
        return np.clip(noisy, 0, 255).astype(np.uint8)
