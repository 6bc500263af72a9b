"""One random stream per subsystem, spawned from the episode seed (common random numbers).

At each reset the env draws one integer from its ``np_random`` (so ``reset(seed=s)`` fixes it)
and spawns a child :class:`numpy.random.SeedSequence` per subsystem from it, in the fixed order
of :data:`SUBSYSTEMS`. A subsystem's draws then depend on the episode seed and on its own
use only: switching the camera off, changing its rate or its mode leaves the encoders', the
sonar's and the calibration's draws unchanged, so paired comparisons share their noise.
"""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class RandomStreams:
    """The episode's generators, one per subsystem, spawned in field order (append new ones at
    the end: earlier streams then keep their draws)."""

    encoders: np.random.Generator  # wheel slip
    sonar: np.random.Generator  # range noise, dropouts, the beam model's misses and crosstalk
    camera_sensor: np.random.Generator  # the rendered camera's gain and pixel noise
    detector: np.random.Generator  # the fast mode's simulated detections
    calibration: np.random.Generator  # wheel, wheelbase and camera calibration errors (reset)
    faults: np.random.Generator  # injected faults' random parts
    world: np.random.Generator  # generated worlds drawn without a seed
    timing: np.random.Generator  # camera latency jitter
    start: np.random.Generator  # the start pose drawn from task.start_* (envs/start_pose.py)

    @classmethod
    def from_seed(cls, seed: int) -> RandomStreams:
        """The streams of episode seed ``seed`` (a non-negative integer)."""
        children = np.random.SeedSequence(seed).spawn(len(SUBSYSTEMS))
        return cls(*(np.random.default_rng(child) for child in children))

    @classmethod
    def draw(cls, rng: np.random.Generator) -> RandomStreams:
        """The streams of an episode seed drawn from ``rng`` (the env's ``np_random``)."""
        return cls.from_seed(int(rng.integers(2**63)))


#: The subsystems, in spawn order.
SUBSYSTEMS = tuple(field.name for field in dataclasses.fields(RandomStreams))
