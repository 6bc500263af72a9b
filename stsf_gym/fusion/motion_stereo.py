"""Range from two frames of one moving camera ("motion stereo"), eq. 8-20.

Convention (fixed; it replaces the paper's mixed signs, see DESIGN "Known errata"):

* camera axes as OpenCV: x right, y down, z forward;
* an image point is ``q = [u, v, f]``: pixel coordinates relative to the principal
  point, with the focal length ``f`` in pixels as third entry, so a scene point
  ``X`` seen in that camera lies on the ray ``X = s q`` with ``s > 0``;
* a point ``X_k`` in camera-k coordinates is ``X_prev = R @ X_k + t`` in camera k-1
  (``R``, ``t``: the robot's motion between the frames, the paper's ``R`` and ``V``);
* the reference plane through the point has unit normal ``n`` in camera-k
  coordinates and ``n . X_k = D`` (eq. 10); ``D`` is the range returned.

Derivation (eq. 11-20 in this convention). From ``n . X_k = D`` the point is
``X_k = (D / n.q_k) q_k`` (eq. 11), so

    alpha q_prev = (R + t n^T / D) q_k                        (eq. 12-13)

a homography with ``a_ij = r_ij + t_i n_j / D``. Dividing rows 1 and 2 by row 3
(eq. 14-15) and multiplying out gives two equations linear in ``D`` (eq. 16-17):
with ``r = R q_k`` and ``q_prev = [u', v', f']``,

    D (f' r_1 - u' r_3) = -(n.q_k) (f' t_1 - u' t_3)
    D (f' r_2 - v' r_3) = -(n.q_k) (f' t_2 - v' t_3)

i.e. ``a D = c`` and ``b D = d``. Stacking them for every point on the plane gives
``A D = B`` (eq. 18), solved by least squares, ``D = (A^T A)^-1 A^T B`` (eq. 19),
which for one point is ``D = (ac + bd) / (a^2 + b^2)`` (eq. 20).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]

MIN_PARALLAX = 1e-6  # default smallest sine of the angle between the two viewing rays


class DegenerateGeometryError(ValueError):
    """The two views do not determine the range (no parallax, ray parallel to plane...)."""


def _validated(
    q_prev: ArrayLike, q_curr: ArrayLike, R: ArrayLike, t: ArrayLike, n: ArrayLike
) -> tuple[Array, Array, Array, Array, Array]:
    """Check shapes and values; return ``q_prev``, ``q_curr`` as ``(N, 3)`` and ``R, t, n``."""
    qp, qc, n = _validated_rays(q_prev, q_curr, n)
    return (qp, qc, *_validated_motion(R, t), n)


def _validated_rays(
    q_prev: ArrayLike, q_curr: ArrayLike, n: ArrayLike
) -> tuple[Array, Array, Array]:
    """The two views' points as ``(N, 3)`` and the plane normal, checked."""
    qp, qc = np.asarray(q_prev, dtype=float), np.asarray(q_curr, dtype=float)
    n = np.asarray(n, dtype=float)
    if qp.shape != qc.shape or qp.shape[-1:] != (3,) or qp.ndim not in (1, 2):
        raise ValueError(
            f"q_prev and q_curr must both have shape (3,) or (N, 3), got {qp.shape}, {qc.shape}"
        )
    if n.shape != (3,):
        raise ValueError(f"need n (3,), got {n.shape}")
    qp, qc = np.atleast_2d(qp), np.atleast_2d(qc)
    if not all(np.isfinite(a).all() for a in (qp, qc, n)):
        raise ValueError("inputs must be finite")
    if (qp[:, 2] <= 0).any() or (qc[:, 2] <= 0).any():
        raise ValueError("the third entry of each image point (the focal length f) must be > 0")
    if abs(np.linalg.norm(n) - 1.0) > 1e-6:
        raise ValueError(f"the plane normal n must be a unit vector, |n| = {np.linalg.norm(n)}")
    return qp, qc, n


def _validated_motion(R: ArrayLike, t: ArrayLike) -> tuple[Array, Array]:
    """The motion ``(R, t)``, checked."""
    R, t = np.asarray(R, dtype=float), np.asarray(t, dtype=float)
    if R.shape != (3, 3) or t.shape != (3,):
        raise ValueError(f"need R (3, 3), t (3,), got {R.shape}, {t.shape}")
    if not (np.isfinite(R).all() and np.isfinite(t).all()):
        raise ValueError("inputs must be finite")
    if np.abs(R @ R.T - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0:
        raise ValueError("R must be a rotation matrix")
    return R, t


def _linear_system(
    qp: Array, qc: Array, R: Array, t: Array, n: Array
) -> tuple[Array, Array, _View, Array]:
    """Rows ``(a, b)`` and ``(c, d)`` of eq. 16-18 per point, and the pieces they are built of
    (the views' terms and ``r = R q_k``).

    With ``M = [[f', 0, -u'], [0, f', -v']]`` per point: ``(a, b) = M R q_k`` and
    ``(c, d) = -(n.q_k) M t``.
    """
    view = _view_terms(qp, qc, n)
    r = qc @ R.T
    A = np.einsum("iab,ib->ia", view.M, r)
    B = -view.nq[:, None] * (view.M @ t)
    return A, B, view, r


class _View(NamedTuple):
    """The parts of eq. 16-20 the motion does not enter."""

    M: Array  # (N, 2, 3): [[f', 0, -u'], [0, f', -v']] per point
    nq: Array  # (N,): n.q_k
    scale: float  # sqrt(sum |q_prev|^2 |q_k|^2), the parallax's normaliser
    ray_in_plane: bool  # a viewing ray of frame k parallel to the plane (n.q_k = 0)


def _view_terms(qp: Array, qc: Array, n: Array) -> _View:
    """:class:`_View` of the two views' points and the plane normal."""
    f, u, v = qp[:, 2], qp[:, 0], qp[:, 1]
    zero = np.zeros_like(f)
    M = np.stack([np.stack([f, zero, -u], -1), np.stack([zero, f, -v], -1)], -2)
    nq = qc @ n
    return _View(
        M,
        nq,
        np.sqrt(np.sum(np.sum(qp**2, axis=1) * np.sum(qc**2, axis=1))),
        bool((np.abs(nq) <= 1e-12 * np.linalg.norm(qc, axis=1)).any()),
    )


def _solve(A: Array, B: Array, t: Array, view: _View, min_parallax: float) -> float:
    """Least-squares ``D`` of eq. 19, refusing degenerate geometry."""
    if not np.any(t):
        raise DegenerateGeometryError(
            "zero baseline (t = 0): a pure rotation shows no parallax, the range is unobservable"
        )
    if view.ray_in_plane:
        raise DegenerateGeometryError("a viewing ray is parallel to the reference plane (n.q = 0)")
    parallax = np.linalg.norm(A) / view.scale  # sine of the angle between the two rays
    if parallax < min_parallax:
        raise DegenerateGeometryError(
            f"the two viewing rays are parallel (parallax {parallax:.2e} < {min_parallax:.0e}): "
            "the baseline is zero or lies along the line of sight"
        )
    D = float(np.sum(A * B) / np.sum(A * A))
    if (D / view.nq <= 0).any():
        raise DegenerateGeometryError(
            f"D = {D:.6g} puts a point at or behind camera k: the views are inconsistent "
            "or too close to degenerate"
        )
    return D


def motion_stereo_range(
    q_prev: ArrayLike,
    q_curr: ArrayLike,
    R: ArrayLike,
    t: ArrayLike,
    n: ArrayLike,
    min_parallax: float = MIN_PARALLAX,
) -> float:
    """Range ``D`` to the reference plane from two frames of one camera, eq. 8-20.

    Args:
        q_prev, q_curr: the point(s) in frames k-1 and k, shape ``(3,)`` or ``(N, 3)``,
            each row ``[u, v, f]`` (see module docstring). ``N`` points on the same plane
            give ``2N`` equations and one least-squares ``D``.
        R, t: motion with ``X_prev = R @ X_k + t``.
        n: unit normal of the plane in camera-k coordinates, ``n . X_k = D``.
        min_parallax: smallest accepted sine of the angle between the two rays.

    Raises:
        DegenerateGeometryError: no baseline, rays without parallax, a ray parallel to
            the plane, or a solution behind the camera.
        ValueError: malformed inputs.
    """
    qp, qc, R, t, n = _validated(q_prev, q_curr, R, t, n)
    A, B, view, _ = _linear_system(qp, qc, R, t, n)
    return _solve(A.ravel(), B.ravel(), t, view, min_parallax)


def motion_stereo_ranges(
    q_prev: ArrayLike,
    q_curr: ArrayLike,
    motions: list[tuple[ArrayLike, ArrayLike]],
    n: ArrayLike,
    min_parallax: float = MIN_PARALLAX,
) -> list[float | None]:
    """:func:`motion_stereo_range` of one pair of views under each of ``motions`` ``(R, t)``
    (a motion and its perturbations, for a Jacobian by finite differences): the same numbers,
    ``None`` where the geometry is degenerate, with the views checked and the terms of eq.
    16-18 that the motion does not enter built once (``R q_k`` too, while ``R`` repeats)."""
    qp, qc, n = _validated_rays(q_prev, q_curr, n)
    view = _view_terms(qp, qc, n)
    ranges: list[float | None] = []
    rotated: tuple[Array, Array] | None = None  # the last R and its (a, b) rows
    for motion in motions:
        R, t = _validated_motion(*motion)
        if rotated is None or not np.array_equal(rotated[0], R):
            rotated = R, np.einsum("iab,ib->ia", view.M, qc @ R.T)
        B = -view.nq[:, None] * (view.M @ t)
        try:
            ranges.append(_solve(rotated[1].ravel(), B.ravel(), t, view, min_parallax))
        except DegenerateGeometryError:
            ranges.append(None)
    return ranges


def _skew(w: Array) -> Array:
    """Cross-product matrices ``[w]_x`` for a stack of vectors ``(..., 3)``."""
    zero = np.zeros(w.shape[:-1])
    x, y, z = w[..., 0], w[..., 1], w[..., 2]
    return np.stack(
        [np.stack([zero, -z, y], -1), np.stack([z, zero, -x], -1), np.stack([-y, x, zero], -1)],
        -2,
    )


def motion_stereo_variance(
    q_prev: ArrayLike,
    q_curr: ArrayLike,
    R: ArrayLike,
    t: ArrayLike,
    n: ArrayLike,
    sigma_px: float,
    cov_t: ArrayLike | None = None,
    cov_rot: ArrayLike | None = None,
) -> float:
    """First-order variance of :func:`motion_stereo_range`'s ``D``.

    Error sources (independent): pixel noise ``sigma_px`` on ``u`` and ``v`` of every
    point in both frames; baseline (odometry) error with covariance ``cov_t`` (3x3);
    a small rotation error ``dphi`` (rotation vector, camera-k axes, the true rotation
    being ``R @ expm([dphi]_x)``) with covariance ``cov_rot`` (3x3).

    The Jacobian is analytic: differentiating eq. 19,
    ``dD = (A^T (dB - D dA) + (B - A D)^T dA) / (A^T A)``, where ``dA`` and ``dB``
    follow from ``(a, b) = M R q_k`` and ``(c, d) = -(n.q_k) M t`` (see
    ``_linear_system``); ``var(D) = g^T Sigma g`` over all error sources.
    """
    return motion_stereo_estimate(q_prev, q_curr, R, t, n, sigma_px, cov_t, cov_rot)[1]


def motion_stereo_estimate(
    q_prev: ArrayLike,
    q_curr: ArrayLike,
    R: ArrayLike,
    t: ArrayLike,
    n: ArrayLike,
    sigma_px: float,
    cov_t: ArrayLike | None = None,
    cov_rot: ArrayLike | None = None,
) -> tuple[float, float]:
    """:func:`motion_stereo_range`'s ``D`` and :func:`motion_stereo_variance`'s variance of it,
    from one solution of eq. 19 (the same numbers as the two calls, at half the cost)."""
    qp, qc, R, t, n = _validated(q_prev, q_curr, R, t, n)
    A, B, view, r = _linear_system(qp, qc, R, t, n)
    D = _solve(A.ravel(), B.ravel(), t, view, MIN_PARALLAX)
    M, nq = view.M, view.nq
    norm2 = np.sum(A * A)
    g_A = (B - 2.0 * D * A) / norm2  # dD/dA per point, (N, 2)
    g_B = A / norm2  # dD/dB per point, (N, 2)
    # pixels of frame k-1: d(a, b)/d(u', v') = -r_3 I, d(c, d)/d(u', v') = (n.q) t_3 I
    g_prev = -r[:, 2:] * g_A + (nq * t[2])[:, None] * g_B
    # pixels of frame k: d(a, b)/d(u, v) = M R[:, :2], d(c, d)/d(u, v) = -(M t) n[:2]^T
    g_curr = np.einsum("iab,bc,ia->ic", M, R[:, :2], g_A)
    g_curr -= np.sum((M @ t) * g_B, axis=1)[:, None] * n[:2]
    var = sigma_px**2 * (np.sum(g_prev**2) + np.sum(g_curr**2))
    if cov_t is not None:
        g_t = -np.einsum("i,iab,ia->b", nq, M, g_B)  # d(c, d)/dt = -(n.q) M
        var += g_t @ np.asarray(cov_t, dtype=float) @ g_t
    if cov_rot is not None:
        dA_dphi = -M @ R @ _skew(qc)  # d(R q)/dphi = -R [q]_x
        g_phi = np.einsum("iab,ia->b", dA_dphi, g_A)
        var += g_phi @ np.asarray(cov_rot, dtype=float) @ g_phi
    return D, float(var)


def stereo_range_bound(Z: ArrayLike, f: float, b: float, sigma_px: float) -> Array | float:
    """Standard deviation of stereo range, ``sqrt(2) Z^2 sigma_px / (f b)``.

    The statistical bound Table I is compared with: depth ``Z``, focal length ``f``
    (pixels), baseline ``b`` and disparity noise from ``sigma_px`` in each image.
    """
    if f <= 0 or b <= 0:
        raise ValueError(f"focal length and baseline must be positive, got f={f}, b={b}")
    bound = np.sqrt(2.0) * np.asarray(Z, dtype=float) ** 2 * sigma_px / (f * b)
    return float(bound) if bound.ndim == 0 else bound
