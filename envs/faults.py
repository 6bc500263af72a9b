"""Fault injection: the timed faults of the ``faults:`` config section
(:mod:`stsf_gym.envs.fault_spec`).

The env calls one :class:`FaultInjector` at fixed points of its cycle:

- :meth:`FaultInjector.reset`, after the robot is placed: every board back in place, then the
  world as it is at time 0;
- :meth:`FaultInjector.before_physics`, with the time the step will end at: boards taken out
  (``landmark_removed``, ``landmark_occluded``) or put in (``outlier_detection``'s decoy, a
  board of a map id at a wrong place) for that time, and ``kidnap`` (the robot teleported);
- :meth:`FaultInjector.observe`, on the observation before the env returns it: the camera,
  sonar and encoder faults.

Camera faults act on the frames taken in their window: ``camera_blackout`` (a black image, no
detections), ``motion_blur`` (a line blur of ``kernel_px`` pixels; on simulated detections an
error of the same spread along the blur), ``dropped_frames`` (the frame never arrives:
``image_new`` 0 and the last delivered frame repeated). Between frames the env repeats its
frame; the injector repeats the delivered (faulted) one instead. With simulated detections
(``camera.mode: fast``) the decoy board is not seen by the simulation, so ``outlier_detection``
adds a copy of a real detection labelled with the fault's id. The injector reads and writes
only the observation keys, so it works in either camera mode.

Every random draw comes from the episode's fault stream and only while a fault acts, so a config
without faults gives the same episodes as before.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from gymnasium import spaces

from stsf_gym.envs.config import LandmarkSpec
from stsf_gym.envs.fault_spec import INSTANT_KINDS, FaultSpec

FRAME_KEYS = (
    "image",
    "camera_pan_tilt",
    "landmark_ids",
    "landmark_points",
    "aided_ids",
    "aided_points",
)
BOARD_KINDS = ("landmark_removed", "landmark_occluded", "outlier_detection")
WHEELS = {"left": 0, "right": 1}


class FaultInjector:
    """Applies ``faults`` to one env's world (``world``, ``robot``) and observations."""

    def __init__(self, faults: tuple[FaultSpec, ...], world, robot, space: spaces.Dict) -> None:
        self.faults, self.world, self.robot = faults, world, robot
        self.tick_limit = int(space["encoders"].high[0])
        self.sonar_low = float(space["sonar"].low[0])
        self.sonar_high = float(space["sonar"].high[0])
        # board body -> (whether the faults put it in rather than take it out, its faults)
        self.boards: dict[int, tuple[bool, list[FaultSpec]]] = {}
        for fault in faults:
            if fault.kind == "outlier_detection":
                decoy = LandmarkSpec(fault.landmark_id, fault.at, fault.facing_deg)
                self.boards[world.add_board(decoy)] = (True, [fault])
            elif fault.kind in BOARD_KINDS:
                body = world.boards[fault.landmark_id]
                self.boards.setdefault(body, (False, []))[1].append(fault)
        self.fired: set[int] = set()
        self.frame: dict | None = None
        self._place_boards(0.0)  # decoys out of sight before the env saves its initial state

    def reset(self) -> None:
        """A new episode: every board back where it was, then the faults of time 0."""
        for body in self.boards:
            self.world.set_board_visible(body, True)
        self._place_boards(0.0)
        self.fired.clear()
        self.frame = None

    def before_physics(self, time: float) -> bool:
        """World faults for the step ending at ``time``; ``True`` when the robot was moved."""
        self._place_boards(time)
        moved = False
        for fault in self._firing("kidnap", time):
            self.robot.teleport(*fault.shift, math.radians(fault.turn_deg))
            moved = True
        return moved

    def observe(self, obs: dict, time: float, rng: np.random.Generator) -> dict:
        """Sensor faults on the observation of ``time`` (changed in place and returned)."""
        if not self.faults:
            return obs
        active = [f for f in self.faults if f.kind not in INSTANT_KINDS and f.active(time)]
        for fault in active:
            if fault.kind == "sonar_dropouts":
                lost = rng.random(obs["sonar"].shape) < fault.probability
                obs["sonar"][lost] = self.sonar_high
            elif fault.kind == "sonar_spurious":
                false = rng.random(obs["sonar"].shape) < fault.probability
                echo = rng.uniform(self.sonar_low, fault.max_range, obs["sonar"].shape)
                spurious = np.where(false, np.minimum(obs["sonar"], echo), obs["sonar"])
                obs["sonar"] = np.clip(spurious, self.sonar_low, self.sonar_high).astype(np.float32)
        for fault in self._firing("encoder_spike", time):
            ticks = obs["encoders"].copy()
            ticks[WHEELS[fault.wheel]] += fault.ticks
            obs["encoders"] = np.clip(ticks, -self.tick_limit, self.tick_limit)
        return self._camera(obs, active, rng)

    def _camera(self, obs: dict, active: list[FaultSpec], rng: np.random.Generator) -> dict:
        if obs["image_new"]:
            dropped = False
            for fault in active:
                if fault.kind == "dropped_frames":
                    dropped |= bool(rng.random() < fault.probability)
                elif fault.kind == "camera_blackout":
                    _blackout(obs)
                elif fault.kind == "motion_blur":
                    _blur(obs, fault, rng)
                elif fault.kind == "outlier_detection" and "landmark_ids" in obs:
                    _mislabel(obs, fault.landmark_id)
            if not dropped:
                self.frame = {k: obs[k].copy() for k in FRAME_KEYS if k in obs}
                return obs
            obs["image_new"] = 0
        if self.frame is not None:  # repeat the last frame delivered, as the camera did
            obs.update({k: v.copy() for k, v in self.frame.items()})
        return obs

    def _place_boards(self, time: float) -> None:
        for body, (decoy, faults) in self.boards.items():
            acting = any(f.active(time) for f in faults)
            self.world.set_board_visible(body, acting if decoy else not acting)

    def _firing(self, kind: str, time: float) -> list[FaultSpec]:
        """Instant faults of ``kind`` due at ``time`` and not fired yet (marked fired)."""
        due = []
        for i, fault in enumerate(self.faults):
            if fault.kind == kind and i not in self.fired and time >= fault.start - 1e-9:
                self.fired.add(i)
                due.append(fault)
        return due


def _blackout(obs: dict) -> None:
    if "image" in obs:
        obs["image"] = np.zeros_like(obs["image"])
    for prefix in ("landmark", "aided"):
        if f"{prefix}_ids" in obs:
            obs[f"{prefix}_ids"] = np.full_like(obs[f"{prefix}_ids"], -1)
            obs[f"{prefix}_points"] = np.zeros_like(obs[f"{prefix}_points"])


def blur_kernel(length_px: float, angle_deg: float) -> np.ndarray:
    """A normalised line kernel ``length_px`` long at ``angle_deg`` (0: along image rows)."""
    size = 2 * math.ceil(length_px / 2) + 1
    line = np.zeros((size, size), np.float32)
    half = (length_px - 1) / 2
    centre = size // 2
    dx, dy = half * math.cos(math.radians(angle_deg)), -half * math.sin(math.radians(angle_deg))
    ends = [(centre - dx, centre - dy), (centre + dx, centre + dy)]
    shift = 8  # sub-pixel bits of cv2.line
    points = [tuple(round(v * (1 << shift)) for v in p) for p in ends]
    cv2.line(line, *points, 1.0, 1, cv2.LINE_AA, shift)
    return line / line.sum()


def _blur(obs: dict, fault: FaultSpec, rng: np.random.Generator) -> None:
    if "image" in obs:
        kernel = blur_kernel(fault.kernel_px, fault.angle_deg)
        obs["image"] = cv2.filter2D(obs["image"], -1, kernel, borderType=cv2.BORDER_REPLICATE)
    if "landmark_ids" in obs:
        # a point smeared uniformly over kernel_px pixels: its centroid's spread along the blur
        angle = math.radians(fault.angle_deg)
        along = np.array([math.cos(angle), -math.sin(angle)], np.float32)
        points = _slot_points(obs)
        offset = rng.standard_normal(points.shape[:2]).astype(np.float32)
        offset *= fault.kernel_px / math.sqrt(12)
        used = (obs["landmark_ids"] >= 0)[:, None] & np.any(points != 0, axis=-1)
        blurred = points + (offset * used)[..., None] * along
        obs["landmark_points"] = blurred.reshape(obs["landmark_points"].shape)


def _mislabel(obs: dict, wrong_id: int) -> None:
    """Add a copy of a detection of another board labelled ``wrong_id`` (an empty slot if any,
    else in place of the original)."""
    ids = obs["landmark_ids"]
    sources = np.flatnonzero((ids >= 0) & (ids != wrong_id))
    if len(sources) == 0:
        return
    empty = np.flatnonzero(ids < 0)
    target = empty[0] if len(empty) else sources[0]
    obs["landmark_ids"] = ids.copy()
    obs["landmark_ids"][target] = wrong_id
    points = _slot_points(obs).copy()
    points[target] = points[sources[0]]
    obs["landmark_points"] = points.reshape(obs["landmark_points"].shape)


def _slot_points(obs: dict) -> np.ndarray:
    """``landmark_points`` as (slot, point, xy), whatever its layout in the observation."""
    return obs["landmark_points"].reshape(len(obs["landmark_ids"]), -1, 2)
