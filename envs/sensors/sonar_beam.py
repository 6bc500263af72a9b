"""The sonar beam model (optional, ``sonar.beam``): what an ultrasonic ring really reads.

After Thrun, Burgard and Fox, *Probabilistic Robotics* (2005), ch. 6.3, and the specular
behaviour of ultrasound on smooth walls (their fig. 6.1):

- **Specular misses**: a smooth surface returns the echo to the transducer only when the beam
  meets it nearly head-on. Each ray of a cone is detected with probability
  ``p(theta) = 1 / (1 + exp((theta - critical_angle) / angle_width))`` of its angle of
  incidence ``theta`` (to the surface normal); a transducer reads its nearest detected ray,
  or ``max_range`` when none is (the echo went elsewhere: the max-range reading ``p_max``).
- **Random readings** (``p_rand``): with probability ``random_prob`` a reading is uniform in
  [min_range, max_range] (phantom echoes, electrical noise).
- **Crosstalk**: when the ring fires all together (no ``firing_order``), a transducer takes a
  neighbour's echo with probability ``crosstalk_prob``; a firing sequence avoids it.

Range noise and dropouts stay those of :class:`~stsf_gym.envs.sensors.sonar.SonarRing`. All
draws come from the episode's sonar stream, and only with the model on.
"""

from __future__ import annotations

import numpy as np

from stsf_gym.envs.config import SonarBeamConfig
from stsf_gym.geometry import compiled

#: the neighbour a transducer's crosstalk comes from: the one before or the one after
NEIGHBOUR_SIDES = np.array([-1, 1])
#: the crosstalk draws of a reading that cannot be crossed (not the whole ring firing together)
NO_DRAWS, NO_SIDES = np.zeros(0, bool), np.zeros(0, np.int64)


def detection_probability(incidence: np.ndarray, cfg: SonarBeamConfig) -> np.ndarray:
    """Chance that a ray meeting a surface at ``incidence`` (rad from its normal) echoes back."""
    critical, width = np.radians(cfg.critical_angle_deg), np.radians(cfg.angle_width_deg)
    return 1.0 / (1.0 + np.exp((np.asarray(incidence) - critical) / width))


def beam_ranges(
    fractions: np.ndarray,
    incidence: np.ndarray,
    max_range: float,
    cfg: SonarBeamConfig,
    rng: np.random.Generator,
) -> np.ndarray:
    """Per transducer, the nearest ray (``fractions`` of max range, ``(T, rays)``) whose echo
    was detected, in metres; ``max_range`` where none was."""
    draws = rng.random(fractions.shape)
    return _nearest_detected(fractions, draws, detection_probability(incidence, cfg), max_range)


def corrupt(
    ranges: np.ndarray,
    transducers: np.ndarray,
    count: int,
    limits: tuple[float, float],
    cfg: SonarBeamConfig,
    simultaneous: bool,
    rng: np.random.Generator,
) -> np.ndarray:
    """Random readings, and crosstalk between neighbours of a ring firing together."""
    crossed, side = NO_DRAWS, NO_SIDES
    if simultaneous and len(ranges) == count:
        crossed = rng.random(count) < cfg.crosstalk_prob
        side = rng.integers(0, 2, count)  # rng.choice([-1, 1], count)'s draw
    random = rng.random(len(ranges)) < cfg.random_prob
    return _corrupted(ranges, transducers, crossed, side, random, rng.uniform(*limits, len(ranges)))


@compiled
def _nearest_detected(
    fractions: np.ndarray, draws: np.ndarray, probability: np.ndarray, max_range: float
) -> np.ndarray:
    """``max_range * np.where(draws < probability, fractions, 1.0).min(axis=1)``: each row's
    nearest detected ray (a NaN kept, as ``min`` keeps it)."""
    nearest = np.empty(fractions.shape[0])
    for t in range(fractions.shape[0]):
        row = fractions[t, 0] if draws[t, 0] < probability[t, 0] else 1.0
        for k in range(1, fractions.shape[1]):
            value = fractions[t, k] if draws[t, k] < probability[t, k] else 1.0
            if row == row and (value != value or value < row):
                row = value
        nearest[t] = max_range * row
    return nearest


@compiled
def _corrupted(
    ranges: np.ndarray,
    transducers: np.ndarray,
    crossed: np.ndarray,
    side: np.ndarray,
    random: np.ndarray,
    values: np.ndarray,
) -> np.ndarray:
    """Each ``crossed`` reading (none when ``crossed`` is empty) the nearer of itself and its
    neighbour on ``side`` (0: the one before, 1: the one after, as the ring read them), then
    each ``random`` one its uniform value: ``np.minimum`` and ``np.where``'s answers, NaN
    kept."""
    count = len(ranges)
    out = ranges.copy()
    for i in range(count):
        if len(crossed) and crossed[i]:
            other = ranges[(transducers[i] + NEIGHBOUR_SIDES[side[i]]) % count]
            if out[i] == out[i] and (other != other or other < out[i]):
                out[i] = other
        if random[i]:
            out[i] = values[i]
    return out
