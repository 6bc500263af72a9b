"""Trajectories in the TUM RGB-D format that evo and the field's other tools read.

One pose per line: ``timestamp tx ty tz qx qy qz qw`` (seconds, metres, unit quaternion of
the body's orientation in the world). A planar pose ``[x, y, yaw]`` has ``z = 0`` and the
rotation about z by ``yaw``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from stsf_gym.io import write_atomic

HEADER = "# timestamp tx ty tz qx qy qz qw\n"


def tum_lines(times: ArrayLike, poses: ArrayLike) -> str:
    """The TUM text of planar ``poses`` ``(N, 3)`` at ``times`` ``(N,)``."""
    times, poses = np.asarray(times, dtype=float), np.asarray(poses, dtype=float)
    if len(times) != len(poses) or poses.ndim != 2 or poses.shape[1] != 3:
        raise ValueError(f"need N times and (N, 3) poses, got {times.shape} and {poses.shape}")
    half = poses[:, 2] / 2.0
    rows = np.column_stack(
        [times, poses[:, :2], np.zeros((len(poses), 3)), np.sin(half), np.cos(half)]
    )
    return HEADER + "".join(" ".join(f"{v:.9f}" for v in row) + "\n" for row in rows)


def write_tum(path: str | Path, times: ArrayLike, poses: ArrayLike) -> Path:
    """Write a planar trajectory as a TUM file (atomically)."""
    return write_atomic(path, tum_lines(times, poses))


def read_tum(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """``(times, poses)`` of a TUM file of planar poses (yaw from the quaternion)."""
    data = np.atleast_2d(np.loadtxt(path, comments="#"))
    qx, qy, qz, qw = data[:, 4:8].T
    yaw = np.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy**2 + qz**2))
    return data[:, 0], np.column_stack([data[:, 1:3], yaw])
