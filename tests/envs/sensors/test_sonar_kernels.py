"""The compiled kernels of the sonar and its plane cast give, to the bit, the numpy
expressions their docstrings name, on random readings with misses, NaNs, readings below the
minimum range and partial rings."""

import numpy as np
import pytest

from stsf_gym.envs.sensors.plane_cast import _hit_fractions
from stsf_gym.envs.sensors.sonar import _incidence_cosines, _readings
from stsf_gym.envs.sensors.sonar_beam import (
    NEIGHBOUR_SIDES,
    NO_DRAWS,
    NO_SIDES,
    _corrupted,
    _nearest_detected,
)
from stsf_gym.geometry import bounded

MAX_RANGE, MIN_RANGE = 4.0, 0.1


def _ranges(rng: np.random.Generator, shape) -> np.ndarray:
    values = rng.uniform(0.0, 1.0, shape)
    values[rng.random(shape) < 0.3] = 1.0  # misses
    values[rng.random(shape) < 0.05] = np.nan
    return values


@pytest.mark.parametrize("seed", range(20))
def test_nearest_detected_is_where_then_min(seed):
    rng = np.random.default_rng(seed)
    fractions = _ranges(rng, (16, int(rng.integers(1, 6))))
    draws, probability = rng.random(fractions.shape), rng.random(fractions.shape)
    expected = MAX_RANGE * np.where(draws < probability, fractions, 1.0).min(axis=1)
    got = _nearest_detected(fractions, draws, probability, MAX_RANGE)
    np.testing.assert_array_equal(got, expected)


@pytest.mark.parametrize("seed", range(20))
def test_corrupted_is_minimum_then_where(seed):
    rng = np.random.default_rng(seed)
    count = 16
    ranges = MAX_RANGE * _ranges(rng, count)
    crossed, side = rng.random(count) < 0.4, rng.integers(0, 2, count)
    random, values = rng.random(count) < 0.2, rng.uniform(MIN_RANGE, MAX_RANGE, count)
    transducers = np.arange(count)
    neighbours = ranges[(transducers + NEIGHBOUR_SIDES[side]) % count]
    crossed_ranges = np.where(crossed, np.minimum(ranges, neighbours), ranges)
    expected = np.where(random, values, crossed_ranges)
    got = _corrupted(ranges, transducers, crossed, side, random, values)
    np.testing.assert_array_equal(got, expected)
    # one transducer of a firing sequence: no crosstalk
    one = _corrupted(ranges[[5]], np.array([5]), NO_DRAWS, NO_SIDES, random[[5]], values[[5]])
    np.testing.assert_array_equal(one, np.where(random[[5]], values[[5]], ranges[[5]]))


@pytest.mark.parametrize("seed", range(20))
def test_readings_are_noise_where_clip_and_float32(seed):
    rng = np.random.default_rng(seed)
    ranges = MAX_RANGE * _ranges(rng, 16)
    normal, dropped = rng.normal(size=16), rng.random(16) < 0.1
    noisy = ranges + normal * (0.02 + 0.01 * ranges)
    noisy = np.where(ranges < MAX_RANGE, noisy, MAX_RANGE)
    noisy[dropped] = MAX_RANGE
    expected = bounded(noisy, MIN_RANGE, MAX_RANGE).astype(np.float32)
    got = _readings(ranges, normal, dropped, 0.02, 0.01, MIN_RANGE, MAX_RANGE)
    assert got.dtype == np.float32
    np.testing.assert_array_equal(got, expected)


@pytest.mark.parametrize("seed", range(20))
def test_hit_fractions_and_incidence_cosines_are_their_numpy_expressions(seed):
    rng = np.random.default_rng(seed)
    t = rng.uniform(0.0, 2 * MAX_RANGE, 40)
    t[rng.random(40) < 0.2] = np.inf
    t[rng.random(40) < 0.05] = np.nan
    normals = rng.normal(size=(40, 2))
    normals /= np.hypot(*normals.T)[:, None]
    expected_normals = np.where((t <= MAX_RANGE)[:, None], normals, 0.0)
    expected = np.where(t <= MAX_RANGE, t / MAX_RANGE, 1.0)
    got = _hit_fractions(t, normals, MAX_RANGE)
    np.testing.assert_array_equal(got, expected)
    np.testing.assert_array_equal(normals, expected_normals)
    directions = 1.0000001 * rng.normal(size=(40, 2))  # products a little past +-1 are clipped
    expected_angles = np.arccos(bounded(-np.sum(normals * directions, axis=1), -1.0, 1.0))
    angles = np.arccos(_incidence_cosines(normals, directions))
    np.testing.assert_array_equal(angles, expected_angles)
