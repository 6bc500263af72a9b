"""Sonar ring: transducers around the body, each a cone of rays cast in one ``rayTestBatch``."""

from __future__ import annotations

import math

import numpy as np

from stsf_gym.envs.config import SonarConfig
from stsf_gym.envs.simulator import Simulator


class SonarRing:
    """``count`` transducers evenly spaced around the body, transducer 0 facing forward and
    the rest counter-clockwise. Each reads the nearest hit among ``rays_per_beam`` rays fanned
    across its ``beam_width_deg`` cone, plus range noise; a dropout reads ``max_range``.
    """

    def __init__(self, cfg: SonarConfig, body_radius: float) -> None:
        if cfg.count < 1 or cfg.rays_per_beam < 1:
            raise ValueError("sonar.count and sonar.rays_per_beam must be at least 1")
        if not 0 < cfg.min_range < cfg.max_range:
            raise ValueError(
                f"sonar ranges must satisfy 0 < min_range < max_range, got "
                f"{cfg.min_range}, {cfg.max_range}"
            )
        self.cfg = cfg
        self.axes = np.arange(cfg.count) * 2 * math.pi / cfg.count  # transducer headings
        half = math.radians(cfg.beam_width_deg) / 2
        spread = np.linspace(-half, half, cfg.rays_per_beam) if cfg.rays_per_beam > 1 else [0.0]
        ray_angles = (self.axes[:, None] + np.asarray(spread)[None, :]).ravel()
        self.origin_radius = body_radius + 0.01  # the ring the rays start from (m)
        # robot-frame ray starts (on the ring, at each transducer) and unit directions
        self._origins = self.origin_radius * np.repeat(
            np.column_stack([np.cos(self.axes), np.sin(self.axes)]), cfg.rays_per_beam, axis=0
        )
        self._directions = np.column_stack([np.cos(ray_angles), np.sin(ray_angles)])

    def true_ranges(self, sim: Simulator, pose: np.ndarray) -> np.ndarray:
        """Noise-free nearest-hit range per transducer from the ring (metres)."""
        x, y, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        rotation = np.array([[c, -s], [s, c]])
        starts = self._origins @ rotation.T + (x, y)
        ends = starts + self.cfg.max_range * self._directions @ rotation.T
        z = np.full((len(starts), 1), self.cfg.height)
        hits = sim.client.rayTestBatch(
            np.hstack([starts, z]).tolist(), np.hstack([ends, z]).tolist()
        )
        fractions = np.array([hit[2] if hit[0] >= 0 else 1.0 for hit in hits])
        return self.cfg.max_range * fractions.reshape(self.cfg.count, -1).min(axis=1)

    def read(self, sim: Simulator, pose: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Noisy float32 ranges, clipped to [min_range, max_range]."""
        cfg = self.cfg
        ranges = self.true_ranges(sim, pose)
        hit = ranges < cfg.max_range
        noisy = ranges + rng.normal(size=cfg.count) * (cfg.noise_std + cfg.noise_std_per_m * ranges)
        noisy = np.where(hit, noisy, cfg.max_range)
        noisy[rng.random(cfg.count) < cfg.dropout_prob] = cfg.max_range
        return np.clip(noisy, cfg.min_range, cfg.max_range).astype(np.float32)
