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

#: the neighbour a transducer's crosstalk comes from: the one before or the one after
NEIGHBOUR_SIDES = np.array([-1, 1])


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
    detected = rng.random(fractions.shape) < detection_probability(incidence, cfg)
    return max_range * np.where(detected, fractions, 1.0).min(axis=1)


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
    ranges = ranges.copy()
    if simultaneous and len(ranges) == count:
        crossed = rng.random(count) < cfg.crosstalk_prob
        side = NEIGHBOUR_SIDES[rng.integers(0, 2, count)]  # rng.choice([-1, 1], count)'s draw
        ranges = np.where(crossed, np.minimum(ranges, ranges[(transducers + side) % count]), ranges)
    random = rng.random(len(ranges)) < cfg.random_prob
    return np.where(random, rng.uniform(*limits, len(ranges)), ranges)
