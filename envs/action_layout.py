"""The action's entries by name: ``v, w`` (drive), ``pan, tilt`` (camera mount), ``stop``, and
``hold`` (a residual policy's gate over a scripted declaration, :mod:`stsf_gym.agents.rl.residual`).

An env's action is a ``Box(-1, 1)`` whose entries follow :data:`ACTION_NAMES` in order, each
present or not: ``v`` and ``w`` always, ``pan`` and ``tilt`` as ``camera.control`` asks,
``stop`` with ``task.stop_action`` (Habitat's STOP: above 0 declares arrival). Code reads an
entry by its name, never by its position, so a wrapper that supplies an entry itself (the
pan pointed from the pose estimate) offers the others in the same order without it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

#: Every entry an action may have, in the order they appear.
ACTION_NAMES = ("v", "w", "pan", "tilt", "stop", "hold")
MOUNT_AXES = {"none": (), "pan": ("pan",), "pan_tilt": ("pan", "tilt")}


def numeric_action(action) -> np.ndarray:
    """``action`` as an array, refused unless its dtype is an integer or a real float: a
    boolean or complex action is the wrong kind, not one to cast (``True`` is not full speed)."""
    raw = np.asarray(action)
    if raw.dtype.kind not in "iuf":
        raise ValueError(f"action must be numeric (int or float), got dtype {raw.dtype}")
    return raw


@dataclass(frozen=True)
class ActionLayout:
    """The names of an action's entries, in order (a subsequence of :data:`ACTION_NAMES`)."""

    names: tuple[str, ...]

    def __post_init__(self) -> None:
        order = [ACTION_NAMES.index(name) for name in self.names if name in ACTION_NAMES]
        if len(order) != len(self.names) or order != sorted(set(order)):
            raise ValueError(f"action entries must follow {ACTION_NAMES}, got {self.names}")
        if self.names[:2] != ("v", "w"):
            raise ValueError(f"an action starts with v and w, got {self.names}")

    @classmethod
    def for_env(cls, camera_control: str, stop_action: bool) -> ActionLayout:
        """The layout of an env with this ``camera.control`` and ``task.stop_action``."""
        return cls(("v", "w", *MOUNT_AXES[camera_control], *(("stop",) if stop_action else ())))

    @property
    def space(self) -> spaces.Box:
        """``Box(-1, 1, (len(names),))``."""
        return spaces.Box(-1.0, 1.0, (len(self.names),), np.float32)

    def __contains__(self, name: str) -> bool:
        return name in self.names

    def index(self, name: str) -> int:
        """The position of entry ``name``."""
        if name not in self.names:
            raise KeyError(f"the action has no entry {name!r}; it has {list(self.names)}")
        return self.names.index(name)

    def without(self, *names: str) -> ActionLayout:
        """This layout less ``names`` (entries a wrapper fills in itself)."""
        return ActionLayout(tuple(n for n in self.names if n not in names))

    def mount(self, action: np.ndarray) -> np.ndarray:
        """The mount entries (``pan``, ``tilt``, those present) of ``action``."""
        return np.array([action[self.index(n)] for n in ("pan", "tilt") if n in self.names])

    def stops(self, action: np.ndarray) -> bool:
        """Whether ``action`` declares arrival (its ``stop`` entry above 0; False without one)."""
        return "stop" in self.names and float(action[self.index("stop")]) > 0.0

    def fill(self, action: np.ndarray, source: ActionLayout, **values: float) -> np.ndarray:
        """An action of this layout from ``action`` (laid out as ``source``) and ``values`` for
        the entries ``source`` lacks."""
        flat = numeric_action(action).astype(np.float32)
        if flat.shape != (len(source.names),):  # (1, n) of a batch is refused, not flattened
            raise ValueError(f"action must have shape ({len(source.names)},), got {flat.shape}")
        given = dict(zip(source.names, flat, strict=True))
        missing = [n for n in self.names if n not in given and n not in values]
        if missing:
            raise ValueError(f"no value for action entries {missing}")
        return np.array([given.get(n, values.get(n)) for n in self.names], np.float32)
