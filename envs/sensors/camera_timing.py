"""When a camera frame's result reaches the robot: exposure, then a processing delay.

A frame exposed at time ``t`` becomes available at ``t + delay_s + |N(0, jitter_s^2)|``
(``camera.latency``; the jitter is drawn from the episode's timing stream). Frames wait in
exposure order and are released at the first step end at or after their availability; when
several are released together the newest is shown and the older ones are lost (a busy
pipeline drops frames), and a frame never overtakes a later one (availability is kept
monotonic). With zero latency every frame is released in the step it is exposed.
"""

from __future__ import annotations

import collections
from dataclasses import dataclass

import numpy as np

from stsf_gym.envs.config import LatencyConfig

TIME_EPS = 1e-9


@dataclass(frozen=True)
class Frame:
    """One exposed frame: its observation keys, true camera pose and mount angles then."""

    exposure: float  # s of simulated time: the middle of the exposure
    available: float  # s: when the robot has it
    camera_obs: dict[str, np.ndarray]
    pose: np.ndarray  # 4x4 world-from-camera (evaluation only)
    pan_tilt: np.ndarray


class FrameQueue:
    """Frames exposed but not yet available."""

    def __init__(self, cfg: LatencyConfig) -> None:
        self.cfg = cfg
        self._waiting: collections.deque[Frame] = collections.deque()

    def reset(self) -> None:
        """Forget the frames still waiting."""
        self._waiting.clear()

    def expose(
        self,
        time: float,
        camera_obs: dict[str, np.ndarray],
        pose: np.ndarray,
        pan_tilt: np.ndarray,
        rng: np.random.Generator,
    ) -> None:
        """Queue the frame exposed at ``time``."""
        delay = self.cfg.delay_s
        if self.cfg.jitter_s > 0:
            delay += abs(float(rng.normal())) * self.cfg.jitter_s
        available = time + delay
        if self._waiting:  # a pipeline: a frame never overtakes an earlier one
            available = max(available, self._waiting[-1].available)
        self._waiting.append(Frame(time, available, camera_obs, pose, pan_tilt))

    def release(self, time: float) -> Frame | None:
        """The newest frame available by ``time`` (older ones available too are dropped)."""
        released = None
        while self._waiting and self._waiting[0].available <= time + TIME_EPS:
            released = self._waiting.popleft()
        return released
