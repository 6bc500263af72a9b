"""Sonar ring: transducers around the body, each a cone of rays cast in one ``rayTestBatch``."""

from __future__ import annotations

import math

import numpy as np

from stsf_gym.envs.config import SonarConfig
from stsf_gym.envs.rendering.scene import Scene
from stsf_gym.envs.sensors.plane_cast import PlaneCaster
from stsf_gym.envs.sensors.sonar_beam import beam_ranges, corrupt
from stsf_gym.envs.simulator import Simulator
from stsf_gym.geometry import compiled
from stsf_gym.validation import ConfigError


class SonarRing:
    """``count`` transducers evenly spaced around the body, transducer 0 facing forward and
    the rest counter-clockwise. Each reads the nearest hit among ``rays_per_beam`` rays fanned
    across its ``beam_width_deg`` cone, plus range noise; a dropout reads ``max_range``. With
    ``sonar.beam.enabled`` the beam model of :mod:`~stsf_gym.envs.sensors.sonar_beam` decides
    which rays echo back (specular misses at shallow incidence), and adds random readings and
    crosstalk.
    """

    def __init__(self, cfg: SonarConfig, body_radius: float) -> None:
        if cfg.count < 1 or cfg.rays_per_beam < 1:
            raise ConfigError("sonar.count and sonar.rays_per_beam must be at least 1")
        if not 0 < cfg.min_range < cfg.max_range:
            raise ConfigError(
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
        self._plane = PlaneCaster(cfg.height) if cfg.cast == "plane" else None
        self._scene_caster = PlaneCaster(cfg.height)  # scene_ranges: any scene, in the plane

    def true_ranges(
        self, sim: Simulator, pose: np.ndarray, transducers: np.ndarray | None = None
    ) -> np.ndarray:
        """Noise-free nearest-hit range (metres) of each of ``transducers`` (default all)."""
        fractions, _ = self._cast(sim, pose, transducers)
        return self.cfg.max_range * fractions.min(axis=1)

    def _cast(
        self, sim: Simulator, pose: np.ndarray, transducers: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Hit fraction of max range (1: no hit) and angle of incidence (rad from the hit
        surface's normal) of every ray, ``(transducers, rays_per_beam)`` each."""
        x, y, _ = pose
        rays = self._rays(transducers)
        starts, directions = self._world_rays(pose, rays)
        if self._plane is not None:
            fractions, normals = self._plane.cast(
                sim.scene, np.array([x, y]), starts, directions, self.cfg.max_range
            )
        else:
            ends = starts + self.cfg.max_range * self._directions[rays] @ _rotation(pose[2]).T
            fractions, normals = _bullet_cast(sim, starts, ends, self.cfg.height)
        incidence = np.arccos(_incidence_cosines(normals, directions))
        shape = (-1, self.cfg.rays_per_beam)
        return fractions.reshape(shape), incidence.reshape(shape)

    def scene_ranges(self, scene: Scene, pose: np.ndarray) -> np.ndarray:
        """Noise-free nearest-hit range (m) of every transducer at ``pose`` against ``scene``'s
        shapes (a map's walls, say), cast in the ring's plane: the ranges :meth:`true_ranges`
        reads in a world of just those shapes."""
        starts, directions = self._world_rays(pose, slice(None))
        fractions, _ = self._scene_caster.cast(
            scene, np.asarray(pose[:2], dtype=float), starts, directions, self.cfg.max_range
        )
        return self.cfg.max_range * fractions.reshape(-1, self.cfg.rays_per_beam).min(axis=1)

    def _world_rays(self, pose: np.ndarray, rays) -> tuple[np.ndarray, np.ndarray]:
        """World starts and unit directions (N, 2 each) of ``rays`` from the ring at ``pose``."""
        rotation = _rotation(pose[2])
        return self._origins[rays] @ rotation.T + tuple(pose[:2]), self._directions[
            rays
        ] @ rotation.T

    def _rays(self, transducers: np.ndarray | None) -> np.ndarray | slice:
        if transducers is None:
            return slice(None)
        per_beam = self.cfg.rays_per_beam
        return (np.asarray(transducers)[:, None] * per_beam + np.arange(per_beam)).ravel()

    def read(
        self,
        sim: Simulator,
        pose: np.ndarray,
        rng: np.random.Generator,
        transducers: np.ndarray | None = None,
    ) -> np.ndarray:
        """Noisy float32 ranges of ``transducers`` (default all), clipped to [min_range,
        max_range]."""
        cfg = self.cfg
        if cfg.beam.enabled:
            fractions, incidence = self._cast(sim, pose, transducers)
            ranges = beam_ranges(fractions, incidence, cfg.max_range, cfg.beam, rng)
            which = np.arange(cfg.count) if transducers is None else np.asarray(transducers)
            limits = (cfg.min_range, cfg.max_range)
            simultaneous = not cfg.firing_order
            ranges = corrupt(ranges, which, cfg.count, limits, cfg.beam, simultaneous, rng)
        else:
            ranges = self.true_ranges(sim, pose, transducers)
        normal = rng.normal(size=len(ranges))
        dropped = rng.random(len(ranges)) < cfg.dropout_prob
        noise = (cfg.noise_std, cfg.noise_std_per_m)
        return _readings(ranges, normal, dropped, *noise, cfg.min_range, cfg.max_range)


def _rotation(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s], [s, c]])


@compiled
def _incidence_cosines(normals: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Cosine of each ray's angle to the normal of the surface it hit (0 without a hit),
    within [-1, 1] (a NaN kept): ``bounded(-np.sum(normals * directions, axis=1), -1, 1)``, up
    to the sign of a zero, which ``arccos`` does not see."""
    cosines = np.empty(len(normals))
    for i in range(len(normals)):
        cosine = -(normals[i, 0] * directions[i, 0] + normals[i, 1] * directions[i, 1])
        cosines[i] = min(max(cosine, -1.0), 1.0) if cosine == cosine else cosine
    return cosines


@compiled
def _readings(
    ranges: np.ndarray,
    normal: np.ndarray,
    dropped: np.ndarray,
    noise_std: float,
    noise_std_per_m: float,
    min_range: float,
    max_range: float,
) -> np.ndarray:
    """Float32 readings of ``ranges``: a hit (nearer than ``max_range``) plus ``normal`` times
    the noise at its range, a miss or a ``dropped`` reading ``max_range``, then clipped to
    [min_range, max_range] (a NaN kept): the numpy ``where``, ``bounded`` and ``astype``'s
    answers."""
    readings = np.empty(len(ranges), np.float32)
    for i in range(len(ranges)):
        r = ranges[i]
        value = r + normal[i] * (noise_std + noise_std_per_m * r) if r < max_range else max_range
        if dropped[i]:
            value = max_range
        if value < min_range:
            value = min_range
        if value > max_range:
            value = max_range
        readings[i] = value
    return readings


def _bullet_cast(
    sim: Simulator, starts: np.ndarray, ends: np.ndarray, height: float
) -> tuple[np.ndarray, np.ndarray]:
    """Hit fraction and 2-D normal of each ray from ``starts`` to ``ends`` (N, 2) at
    ``height``, by PyBullet's ``rayTestBatch`` (the reference the plane cast is tested
    against)."""
    z = np.full((len(starts), 1), height)
    hits = sim.client.rayTestBatch(np.hstack([starts, z]).tolist(), np.hstack([ends, z]).tolist())
    fractions = np.array([hit[2] if hit[0] >= 0 else 1.0 for hit in hits])
    normals = np.array([hit[4][:2] if hit[0] >= 0 else (0.0, 0.0) for hit in hits])
    return fractions, normals
