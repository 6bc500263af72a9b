"""The ``faults:`` config section: timed sensor and world faults (applied by
:mod:`stsf_gym.envs.faults`).

Each entry has a ``kind``, a ``start`` (s of simulated time) and exactly the parameters its kind
takes (:data:`FAULT_PARAMETERS`); a parameter another kind takes is an error, so a misplaced
key is never silently ignored. Window faults act for ``start <= t < start + duration``;
``landmark_removed`` acts from ``start`` to the episode's end; ``encoder_spike`` and ``kidnap``
act once, in the first step that ends at or after ``start``. Example::

    faults:
      - {kind: camera_blackout, start: 30.0, duration: 4.0}
      - {kind: kidnap, start: 60.0, shift: [0.3, 0.1], turn_deg: 8.0}
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Annotated, Literal

from stsf_gym.validation import Degrees, NonNegative, Positive, Probability, Range, require

FaultKind = Literal[
    "camera_blackout",
    "motion_blur",
    "dropped_frames",
    "landmark_removed",
    "landmark_occluded",
    "outlier_detection",
    "sonar_dropouts",
    "sonar_spurious",
    "encoder_spike",
    "kidnap",
]

#: The parameters each kind requires (and the only ones it accepts), besides ``start``.
FAULT_PARAMETERS: dict[str, tuple[str, ...]] = {
    "camera_blackout": ("duration",),  # frames all dark / no detections
    "motion_blur": ("duration", "kernel_px", "angle_deg"),  # line blur of kernel_px pixels
    "dropped_frames": ("duration", "probability"),  # each frame lost with probability
    "landmark_removed": ("landmark_id",),  # board gone from the world (still in the map)
    "landmark_occluded": ("duration", "landmark_id"),  # board hidden for a while
    "outlier_detection": ("duration", "landmark_id", "at", "facing_deg"),  # a decoy board
    "sonar_dropouts": ("duration", "probability"),  # each reading lost to max range
    "sonar_spurious": ("duration", "probability", "max_range"),  # false short echoes
    "encoder_spike": ("wheel", "ticks"),  # ticks added to one wheel's count in one step
    "kidnap": ("shift", "turn_deg"),  # robot teleported; the encoders notice nothing
}
INSTANT_KINDS = ("encoder_spike", "kidnap")


@dataclass(frozen=True)
class FaultSpec:
    """One timed fault. Parameters a kind does not take stay ``None`` (not given)."""

    kind: FaultKind
    start: NonNegative = 0.0  # s of simulated time
    duration: Positive = None  # s
    kernel_px: Annotated[float, Range(ge=1, le=100)] = None  # blur length (pixels)
    angle_deg: Degrees = None  # blur direction in the image, 0 = along its rows
    probability: Probability = None  # per frame (dropped_frames) or per reading (sonar)
    landmark_id: Annotated[int, Range(ge=0)] = None  # a map landmark's id
    at: tuple[float, float] = None  # decoy board: a point on a wall centre line (m)
    facing_deg: Degrees = None  # decoy board: world yaw of its outward normal
    max_range: Positive = None  # false echoes are uniform in [sonar.min_range, max_range] (m)
    wheel: Literal["left", "right"] = None
    ticks: int = None  # added to the wheel's tick delta (either sign)
    shift: tuple[float, float] = None  # kidnap: world-frame displacement dx, dy (m)
    turn_deg: Degrees = None  # kidnap: yaw change about the robot's own axis

    def __post_init__(self) -> None:
        wanted = FAULT_PARAMETERS[self.kind]
        for f in fields(self):
            if f.name in ("kind", "start"):
                continue
            given = getattr(self, f.name) is not None
            require(given or f.name not in wanted, f.name, f"is required by kind {self.kind!r}")
            require(
                not given or f.name in wanted,
                f.name,
                f"is not a parameter of kind {self.kind!r} (it takes: {', '.join(wanted)})",
            )
        if self.kind in INSTANT_KINDS:
            require(self.start > 0, "start", f"of an instant fault must be > 0, got {self.start}")
        if self.kind == "encoder_spike":
            require(self.ticks != 0, "ticks", "must not be 0")

    @property
    def end(self) -> float | None:
        """When the fault stops acting (s), ``None`` for one that lasts to the episode's end."""
        if self.kind in INSTANT_KINDS:
            return self.start
        return None if self.duration is None else self.start + self.duration

    def active(self, time: float) -> bool:
        """Whether a window fault acts at simulated time ``time``."""
        end = self.end
        return self.start - 1e-9 <= time and (end is None or time < end - 1e-9)


def fault_span(faults: tuple[FaultSpec, ...]) -> tuple[float, float | None]:
    """First start, and last end of the faults that end (``None`` when none does), of a set."""
    if not faults:
        raise ValueError("an empty fault set has no span")
    ends = [f.end for f in faults if f.end is not None]
    return min(f.start for f in faults), max(ends) if ends else None
