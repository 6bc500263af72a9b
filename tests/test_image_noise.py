import numpy as np
import pytest

from envs.sensors.image_noise import ImageNoise

SHAPE = (60, 80, 3)


def test_noise_is_gaussian_with_the_configured_spread_and_clipped():
    rng = np.random.default_rng(0)
    noise = ImageNoise(3.0, SHAPE)
    noise.reset(rng)
    grey = np.full(SHAPE, 128, np.uint8)
    diffs = np.stack([noise(grey, rng).astype(float) - 128 for _ in range(20)])
    assert diffs.std() == pytest.approx(3.0, rel=0.05)
    assert abs(diffs.mean()) < 0.05
    assert np.all(diffs == np.rint(diffs))
    black = noise(np.zeros(SHAPE, np.uint8), rng)
    assert black.dtype == np.uint8 and black.min() == 0 and 0 < black.mean() < 3


def test_same_seed_same_noise_and_zero_sigma_passes_through():
    frames = []
    for _ in range(2):
        rng = np.random.default_rng(7)
        noise = ImageNoise(2.0, SHAPE)
        noise.reset(rng)
        frames.append([noise(np.full(SHAPE, 100, np.uint8), rng) for _ in range(3)])
    np.testing.assert_array_equal(frames[0], frames[1])
    assert not np.array_equal(frames[0][0], frames[0][1])  # a new window each frame
    image = np.arange(np.prod(SHAPE)).reshape(SHAPE).astype(np.uint8)
    assert ImageNoise(0.0, SHAPE)(image, np.random.default_rng(0)) is image
