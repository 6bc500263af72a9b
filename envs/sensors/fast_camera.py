"""Fast sensor mode: landmark detections simulated from the true camera pose, no rendering.

The rendered pipeline draws the frame and the estimator's detector finds the boards in it. In
the fast mode (``camera.mode: fast``) the env skips the drawing and reports what the detector
would have found, with the detector's statistics fitted on rendered frames
(``benchmarks/fast_sensor_fit.py`` writes the ``camera.fast`` numbers):

- **which boards**: every board wholly in the frame, facing the camera and not occluded (the
  same test as ``CorridorEnv.landmarks_in_view``) is detected with probability
  ``1 / (1 + exp(-(s - detect_size_px) / detect_size_scale))``, where ``s`` is the board's
  apparent size in pixels: the shorter of its mean projected width and height. That one number
  carries both distance and viewing angle (foreshortening), as it does for the detector,
  whose smallest searched board is ``min_board_px`` wide;
- **where its squares are**: the true projection (K and the lens's distortion, as
  ``cv2.projectPoints``) of every lit square's centre plus
  independent Gaussian errors of ``feature_noise_px`` per axis;
- **false detections**: a Poisson number per frame (mean ``false_detection_rate``) of phantom
  boards with a random map id, fronto-parallel 2-6 m ahead at a random place in the frame.

- **what a track-aided search would find** (STSF's matching, :mod:`stsf_gym.vision.predicted`):
  a board in view that the detector missed is findable, by a search where a track predicts it,
  with probability ``1 / (1 + exp(-(s - aided_size_px) / aided_size_scale))``, fitted by the
  same tool on the same rendered views (the predicted matcher given the board's corners off by
  a track's error). Findable boards go to the ``aided_ids`` / ``aided_points`` slots (the image
  holds them: a rendered frame would too); an estimator uses one only where its own prediction
  puts the board within its search radius (:mod:`stsf_gym.estimators.frame_detector`). Their
  draws come from a stream of their own (spawned from the episode's seed, so the plain
  detections are drawn exactly as without it).

The observation holds ``max_detections`` slots: ``landmark_ids`` (-1 for an empty slot) and
``landmark_points``, flat (slots x 2 grid^2): each slot's lit-square centres as ``x0, y0, x1,
y1, ...`` in :func:`stsf_gym.vision.landmarks.square_centres` order, zero past the last square
(``reshape(slots, -1, 2)`` gives the points; flat because SB3 policies take 1-D vectors); the
same for ``aided_ids`` / ``aided_points``.
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from stsf_gym.envs.config import FastCameraConfig
from stsf_gym.envs.sensors.camera import PinholeCamera
from stsf_gym.envs.worlds.corridor import CorridorWorld
from stsf_gym.geometry import clamp
from stsf_gym.vision.landmarks import square_centres

PHANTOM_DEPTH = (2.0, 6.0)  # m, range of a false detection's depth
NEXT_CORNER = [1, 2, 3, 0]  # each corner's successor round the board


def apparent_size_px(camera: PinholeCamera, world_from_camera: np.ndarray, corners):
    """The shorter of a board's mean projected width and height (pixels): a float for one
    board's corners (4, 3), an array (N,) for N boards' (N, 4, 3), projected at once."""
    corners = np.asarray(corners, float)
    uv = camera.project(world_from_camera, corners.reshape(-1, 3)).reshape(-1, 4, 2)
    sizes = board_sizes_px(uv)
    return float(sizes[0]) if corners.ndim == 2 else sizes


def board_sizes_px(corners_uv: np.ndarray) -> np.ndarray:
    """The shorter of each board's mean width and height (pixels), (N,), from its corners in
    the image (N, 4, 2)."""
    sides = np.linalg.norm(corners_uv - corners_uv[:, NEXT_CORNER], axis=2)  # t, r, b, l
    return np.minimum(sides[:, 0] + sides[:, 2], sides[:, 1] + sides[:, 3]) / 2


def detection_probability(size_px: np.ndarray | float, cfg: FastCameraConfig) -> np.ndarray:
    """Probability that the detector finds a board of apparent size ``size_px``."""
    return logistic(size_px, cfg.detect_size_px, cfg.detect_size_scale)


def aided_probability(size_px: np.ndarray | float, cfg: FastCameraConfig) -> np.ndarray:
    """Probability that a track-aided search finds a board the detector missed."""
    return logistic(size_px, cfg.aided_size_px, cfg.aided_size_scale)


def logistic(size_px: np.ndarray | float, centre: float, width: float) -> np.ndarray:
    """The logistic function of ``size_px`` with its ``centre`` and ``width`` (px)."""
    if isinstance(size_px, float):  # one board: the same operations on one float
        return 1.0 / (1.0 + np.exp(-clamp((size_px - centre) / width, 50.0)))
    z = (np.asarray(size_px, dtype=float) - centre) / width
    return 1.0 / (1.0 + np.exp(-np.clip(z, -50, 50)))


class SimulatedDetector:
    """The detector's output for a camera pose, drawn from its fitted statistics.

    Observation: ``landmark_ids`` ``Box((L,), int64)`` and ``landmark_points``
    ``Box((L * 2 grid^2,), float32)`` (see the module's docstring).
    """

    def __init__(self, cfg: FastCameraConfig, camera: PinholeCamera, world: CorridorWorld) -> None:
        self.cfg, self.camera, self.world = cfg, camera, world
        self.pattern = world.cfg.landmark_pattern
        self.landmarks = {lm.id: lm for lm in world.landmarks}
        self.slots = cfg.max_detections
        self.values_per_slot = 2 * self.pattern.grid**2
        self.frame = self.empty()
        self.aided = self.empty()
        self.aided_rng = np.random.default_rng(0)

    def observation_space(self) -> dict[str, spaces.Space]:
        """The observation keys this mode adds: the detections and the track-aided candidates."""
        span = 2 * max(self.camera.width, self.camera.height)
        ids = spaces.Box(-1, self.pattern.max_id, (self.slots,), np.int64)
        points = spaces.Box(-span, span, (self.slots * self.values_per_slot,), np.float32)
        return {
            "landmark_ids": ids,
            "landmark_points": points,
            "aided_ids": ids,
            "aided_points": points,
        }

    def reset(self, rng: np.random.Generator) -> None:
        """Start an episode: no detections; the track-aided draws get a stream of their own."""
        self.frame = self.aided = self.empty()
        # its own stream, spawned without a draw from ``rng``: the plain detections stay as
        # they were drawn before track-aided slots existed
        self.aided_rng = np.random.default_rng(rng.bit_generator.seed_seq.spawn(1)[0])

    def capture(self, pose: np.ndarray, rng: np.random.Generator) -> None:
        """Detect the boards in view from the camera pose ``pose`` (4x4), and the ones the
        track-aided matcher could find.
        """
        visible, corners_uv = self.world.boards_in_view(self.camera, pose)
        sizes = dict(zip(visible, board_sizes_px(corners_uv).tolist(), strict=True))
        self.frame = self.detect(pose, sizes, rng)
        found = set(self.frame[0].tolist())
        missed = {i: size for i, size in sizes.items() if i not in found}
        self.aided = self.findable(pose, missed, self.aided_rng)

    def observe(self) -> dict[str, np.ndarray]:
        """The last frame's observation keys."""
        (ids, points), (aided_ids, aided_points) = self.frame, self.aided
        return {
            "landmark_ids": ids.copy(),
            "landmark_points": points.copy(),
            "aided_ids": aided_ids.copy(),
            "aided_points": aided_points.copy(),
        }

    def findable(
        self, world_from_camera: np.ndarray, missed: dict[int, float], rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        """The boards in view the detector missed (id: apparent size in pixels, in view order)
        that a track-aided search would find."""
        found = []
        for landmark_id, size in missed.items():
            landmark = self.landmarks[landmark_id]
            if rng.random() < aided_probability(size, self.cfg):
                found.append(
                    (landmark_id, self.camera.project(world_from_camera, landmark.square_centres))
                )
        return self._slots(found, rng)

    def empty(self) -> tuple[np.ndarray, np.ndarray]:
        """Slots with nothing detected."""
        return (
            np.full(self.slots, -1, np.int64),
            np.zeros(self.slots * self.values_per_slot, np.float32),
        )

    def detect(
        self, world_from_camera: np.ndarray, visible: dict[int, float], rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        """``(landmark_ids, landmark_points)`` of one frame; ``visible`` from ray tests (id:
        apparent size in pixels, in view order)."""
        found = []
        for landmark_id, size in visible.items():
            landmark = self.landmarks[landmark_id]
            if rng.random() < detection_probability(size, self.cfg):
                found.append(
                    (landmark_id, self.camera.project(world_from_camera, landmark.square_centres))
                )
        for _ in range(rng.poisson(self.cfg.false_detection_rate)):
            found.append(self._phantom(rng))
        return self._slots(found, rng)

    def _slots(self, found: list, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Slots of ``(id, true pixels)`` pairs, the pixels with the detector's noise."""
        ids, points = self.empty()
        for slot, (landmark_id, uv) in enumerate(found[: self.slots]):
            noisy = uv + rng.normal(0.0, self.cfg.feature_noise_px, uv.shape)
            ids[slot] = landmark_id
            start = slot * self.values_per_slot
            points[start : start + noisy.size] = noisy.ravel()
        return ids, points

    def _phantom(self, rng: np.random.Generator) -> tuple[int, np.ndarray]:
        """A board of a random map id, fronto-parallel at a random depth and place."""
        landmark_id = int(rng.choice(sorted(self.landmarks)))
        plane = square_centres(landmark_id, self.pattern)
        depth = rng.uniform(*PHANTOM_DEPTH)
        half = self.pattern.size / 2 * self.camera.focal_px / depth
        centre = rng.uniform([half, half], [self.camera.width - half, self.camera.height - half])
        uv = centre + plane * np.array([1.0, -1.0]) * self.camera.focal_px / depth
        return landmark_id, uv
