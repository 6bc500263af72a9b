"""SE(2) helpers for planar poses ``[x, y, theta]``.

A pose ``a`` is the frame whose origin is ``(x, y)`` and whose x axis points at
``theta``, expressed in some parent frame. Composition ``a (+) b`` places ``b``
(given in frame ``a``) into the parent frame; ``(-) a`` is the parent frame seen
from ``a``. These are the homogeneous transforms ``T`` of the paper's eq. 3.

Every function accepts a single pose of shape ``(3,)`` or a stack ``(..., 3)``
and broadcasts like numpy; Jacobians then have shape ``(..., 3, 3)``.

:class:`OdometryCalibration` is the wheel geometry a differential-drive robot believes in:
what turns encoder ticks into wheel travel (the env draws it per episode, the estimators use it).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from stsf_gym.validation import Count, RobotLength

Array = NDArray[np.float64]
Kernel = TypeVar("Kernel", bound=Callable)


def compiled(function: Kernel) -> Kernel:
    """``function`` compiled with numba on its first call, for per-step loops over tens of rows
    that numpy would dispatch a dozen times: with numpy's floating-point semantics, so a kernel
    gives the numpy code it replaces to the bit (no ``fastmath``: IEEE operations in the
    written order, no fused multiply-add; numpy's error model: a division by zero gives
    ``inf`` or ``nan``, not an exception), its machine code cached on disk beside the module
    so that only the first process on a machine compiles it."""
    return numba.njit(cache=True, error_model="numpy", fastmath=False)(function)


def bounded(values: ArrayLike, low: ArrayLike, high: ArrayLike) -> NDArray:
    """``np.clip(values, low, high)`` to the bit, NaN kept, in two ufunc calls: ``np.clip``
    passes through three layers of Python first, which on the few numbers of a step's
    observation cost more than the clipping."""
    return np.minimum(np.maximum(values, low), high)


def clamp(value: float, bound: float) -> float:
    """One float within ``[-bound, bound]``: ``np.clip``'s result to the bit, NaN kept, without
    an array's call overhead."""
    return min(max(value, -bound), bound)


def wrap_angle(angle: ArrayLike) -> Array:
    """Wrap angles (radians) to the half-open interval ``(-pi, pi]``."""
    if isinstance(angle, float):  # one angle: Python's float modulo is np.mod's, to the bit
        return np.float64(math.pi - (math.pi - angle) % math.tau)
    angle = np.asarray(angle, dtype=float)
    return np.pi - np.mod(np.pi - angle, 2.0 * np.pi)


def rot2(theta: ArrayLike) -> Array:
    """Rotation matrix ``R(theta) = [[c, -s], [s, c]]``, shape ``(..., 2, 2)``."""
    if isinstance(theta, float):  # one angle: the same ufuncs, the matrix written out
        c, s = np.cos(theta), np.sin(theta)
        return np.array([[c, -s], [s, c]])
    theta = np.asarray(theta, dtype=float)
    c, s = np.cos(theta), np.sin(theta)
    rot = np.empty((*theta.shape, 2, 2))
    rot[..., 0, 0], rot[..., 0, 1], rot[..., 1, 0], rot[..., 1, 1] = c, -s, s, c
    return rot


def compose(a: ArrayLike, b: ArrayLike) -> Array:
    """``a (+) b``: pose ``b`` (given in frame ``a``) expressed in ``a``'s parent frame."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return _composed(a, b, (rot2(a[..., 2]) @ b[..., :2, None])[..., 0])


def _composed(a: Array, b: Array, rb: Array) -> Array:
    """:func:`compose` given ``rb``, b's offset rotated into a's parent frame."""
    if a.ndim == b.ndim == 1:  # one pose each: filled, not concatenated
        composed = np.empty(3)
        composed[:2] = a[:2] + rb
        composed[2] = wrap_angle(float(a[2] + b[2]))
        return composed
    return np.concatenate([a[..., :2] + rb, wrap_angle(a[..., 2] + b[..., 2])[..., None]], -1)


def inverse(a: ArrayLike) -> Array:
    """``(-) a``: the parent frame expressed in frame ``a``."""
    a = np.asarray(a, dtype=float)
    xy = -(np.swapaxes(rot2(a[..., 2]), -1, -2) @ a[..., :2, None])[..., 0]
    return np.concatenate([xy, wrap_angle(-a[..., 2])[..., None]], -1)


def compose_jacobians(a: ArrayLike, b: ArrayLike) -> tuple[Array, Array]:
    """Jacobians ``(d(a (+) b)/da, d(a (+) b)/db)`` of :func:`compose`."""
    return compose_with_jacobians(a, b)[1:]


def compose_with_jacobians(a: ArrayLike, b: ArrayLike) -> tuple[Array, Array, Array]:
    """:func:`compose` and :func:`compose_jacobians` at once: ``a (+) b``, ``d/da``, ``d/db``."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    rot = rot2(a[..., 2])
    rb = (rot @ b[..., :2, None])[..., 0]  # b's offset, rotated into the parent
    return (_composed(a, b, rb), *_compose_jacobians(rot, rb))


def _compose_jacobians(rot: Array, rb: Array) -> tuple[Array, Array]:
    """:func:`compose_jacobians` given a's rotation and b's rotated offset ``rb``."""
    if rb.ndim == 1:  # one pose: written out
        ja = np.array([[1.0, 0.0, -rb[1]], [0.0, 1.0, rb[0]], [0.0, 0.0, 1.0]])
        jb = np.array([[rot[0, 0], rot[0, 1], 0.0], [rot[1, 0], rot[1, 1], 0.0], [0.0, 0.0, 1.0]])
        return ja, jb
    shape = rb.shape[:-1]  # a's and b's leading axes, broadcast
    ja = np.zeros((*shape, 3, 3))
    ja.reshape(*shape, 9)[..., ::4] = 1.0  # the identity: every fourth of the nine entries
    ja[..., 0, 2] = -rb[..., 1]
    ja[..., 1, 2] = rb[..., 0]
    jb = np.zeros((*shape, 3, 3))
    jb[..., :2, :2] = rot
    jb[..., 2, 2] = 1.0
    return ja, jb


def inverse_jacobian(a: ArrayLike) -> Array:
    """Jacobian ``d((-) a)/da`` of :func:`inverse`."""
    a = np.asarray(a, dtype=float)
    rot_t = np.swapaxes(rot2(a[..., 2]), -1, -2)
    inv_xy = -(rot_t @ a[..., :2, None])[..., 0]  # as in inverse()
    jac = np.zeros((*a.shape[:-1], 3, 3))
    jac[..., :2, :2] = -rot_t
    jac[..., 0, 2] = inv_xy[..., 1]
    jac[..., 1, 2] = -inv_xy[..., 0]
    jac[..., 2, 2] = -1.0
    return jac


def to_homogeneous(a: ArrayLike) -> Array:
    """The 3x3 homogeneous matrix ``[[R(theta), (x, y)], [0, 0, 1]]`` of a pose."""
    a = np.asarray(a, dtype=float)
    mat = np.zeros((*a.shape[:-1], 3, 3))
    mat[..., :2, :2] = rot2(a[..., 2])
    mat[..., :2, 2] = a[..., :2]
    mat[..., 2, 2] = 1.0
    return mat


def from_homogeneous(mat: ArrayLike) -> Array:
    """The pose ``[x, y, theta]`` of a 3x3 homogeneous matrix."""
    mat = np.asarray(mat, dtype=float)
    theta = np.arctan2(mat[..., 1, 0], mat[..., 0, 0])
    return np.concatenate([mat[..., :2, 2], wrap_angle(theta)[..., None]], -1)


def to_se3(a: ArrayLike) -> Array:
    """The 4x4 world-from-robot transform of a planar pose (robot frame on the floor, z up)."""
    a = np.asarray(a, dtype=float)
    mat = np.zeros((*a.shape[:-1], 4, 4))
    mat[..., :2, :2] = rot2(a[..., 2])
    mat[..., :2, 3] = a[..., :2]
    mat[..., 2, 2] = mat[..., 3, 3] = 1.0
    return mat


def compose_gaussian(a: ArrayLike, cov_a: ArrayLike, b: ArrayLike, cov_b: ArrayLike):
    """``a (+) b`` with first-order covariance ``J_a C_a J_a^T + J_b C_b J_b^T``
    (independent ``a`` and ``b``): e.g. an odometry increment added to a motion."""
    composed, j_a, j_b = compose_with_jacobians(a, b)
    return composed, j_a @ np.asarray(cov_a) @ j_a.T + j_b @ np.asarray(cov_b) @ j_b.T


@dataclass(frozen=True)
class OdometryCalibration:
    """The robot's believed odometry parameters (not the truth when calibration errors are on)."""

    ticks_per_rev: Count
    wheel_radius_left: RobotLength
    wheel_radius_right: RobotLength
    wheelbase: RobotLength

    def wheel_travel(self, ticks: np.ndarray) -> np.ndarray:
        """Distance (m) each wheel rolled for tick counts [left, right]."""
        radii = np.array([self.wheel_radius_left, self.wheel_radius_right])
        return np.asarray(ticks, dtype=float) * 2 * math.pi / self.ticks_per_rev * radii
