"""Measurement tracks carried into the current frame, eq. 3, with their joint covariance.

A landmark track holds, for frames ``j = 1..k`` (0-based below, current frame last):
the measurement ``z_j`` (the landmark's pose ``[x, y, theta]`` in the robot frame
at frame ``j``) with covariance ``C_j``, and the odometry increment ``u_j`` (pose
of frame ``j+1`` in frame ``j``) with covariance ``Q_j``. Eq. 3 carries every set
into the current frame, ``TS(j) = T_kj (+) z_j``, where ``T_kj`` (the pose of frame
``j`` in frame ``k``) composes the increments ``u_j .. u_{k-1}``.

Errors, to first order. A small rigid motion relative to the current frame, the
twist ``e = [v_x, v_y, omega]``, moves a pose ``p`` by ``H(p) e`` with
``H(p) = [[1, 0, -p_y], [0, 1, p_x], [0, 0, 1]]``. An error ``du_i`` in increment ``i``
moves all frames ``j <= i`` rigidly by the same twist ``L_i du_i``, so

    dTS(j) = J_j dz_j + H(TS(j)) sum_{i >= j} L_i du_i

and, with ``Gamma_i = L_i Q_i L_i^T`` and ``S_j = sum_{i >= j} Gamma_i``, the joint
covariance has the blocks

    sigma_jl = delta_jl J_j C_j J_j^T + H(TS(j)) S_max(j, l) H(TS(l))^T.

The shared ``S`` is the correlation between sets; it is kept in factored form by
:class:`~stsf_gym.fusion.covariance.TrackCovariance`. Scalar range tracks have the
same structure with ``H = J = L = 1``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from stsf_gym.fusion.covariance import TrackCovariance
from stsf_gym.fusion.temporal import Method, STSFResult, stsf_fuse
from stsf_gym.geometry import compose, compose_gaussian, compose_jacobians, inverse, rot2

Array = NDArray[np.float64]


def _twist_jacobian(xy: Array) -> Array:
    """``H(p)``: motion of poses at ``xy`` under a small twist of their frame, ``(k, 3, 3)``."""
    h = np.broadcast_to(np.eye(3), (*xy.shape[:-1], 3, 3)).copy()
    h[..., 0, 2] = -xy[..., 1]
    h[..., 1, 2] = xy[..., 0]
    return h


def transform_pose_track(
    zs: ArrayLike, covs: ArrayLike, us: ArrayLike, qs: ArrayLike
) -> tuple[Array, TrackCovariance]:
    """``TS(j)`` of eq. 3 for pose measurements, and their joint covariance.

    Args:
        zs, covs: measurements ``z_j`` ``(k, 3)`` and covariances ``C_j`` ``(k, 3, 3)``.
        us, qs: increments ``u_j`` ``(k-1, 3)`` and covariances ``Q_j`` ``(k-1, 3, 3)``.

    Returns:
        ``ts`` ``(k, 3)``, the landmark pose in the current robot frame once per set,
        and the joint covariance (``.dense()`` gives the ``(3k, 3k)`` matrix).
    """
    zs, covs = np.asarray(zs, dtype=float), np.asarray(covs, dtype=float)
    us, qs = np.asarray(us, dtype=float).reshape(-1, 3), np.asarray(qs, dtype=float)
    k = zs.shape[0]
    if zs.shape != (k, 3) or covs.shape != (k, 3, 3) or us.shape != (k - 1, 3):
        raise ValueError(
            f"need zs (k, 3), covs (k, 3, 3), us (k-1, 3); got {zs.shape}, {covs.shape}, {us.shape}"
        )
    qs = qs.reshape(-1, 3, 3)
    if qs.shape != (k - 1, 3, 3):
        raise ValueError(f"qs must have shape ({k - 1}, 3, 3), got {qs.shape}")
    # odometry poses in frame 0, then T_kj: the pose of frame j in the current frame
    heading = np.concatenate([[0.0], np.cumsum(us[:, 2])])
    offsets = (rot2(heading[:-1]) @ us[:, :2, None])[..., 0]
    odo = np.column_stack([np.cumsum(np.vstack([np.zeros(2), offsets]), axis=0), heading])
    t_kj = compose(inverse(odo[-1]), odo)
    ts = compose(t_kj, zs)
    _, j_z = compose_jacobians(t_kj, zs)
    # An error du_i moves frame i+1 relative to frame i. Seen from frame k (fixed to
    # frames > i) every frame j <= i moves by the twist L_i du_i: the translation error
    # in frame i's axes, -R(theta_ki) du_xy, and the rotation error, -dtheta about the
    # origin p of frame i+1, which adds the translation [-p_y, p_x] dtheta.
    lin = np.zeros((k - 1, 3, 3))
    lin[:, :2, :2] = -rot2(t_kj[:-1, 2])
    lin[:, 0, 2], lin[:, 1, 2], lin[:, 2, 2] = -t_kj[1:, 1], t_kj[1:, 0], -1.0
    cov = TrackCovariance(
        meas=j_z @ covs @ np.swapaxes(j_z, -1, -2),
        h=_twist_jacobian(ts[:, :2]),
        gammas=lin @ qs @ np.swapaxes(lin, -1, -2),
    )
    return ts, cov


def transform_range_track(
    ranges: ArrayLike, variances: ArrayLike, steps: ArrayLike, step_variances: ArrayLike
) -> tuple[Array, TrackCovariance]:
    """``TS(j)`` of eq. 3 for scalar ranges (e.g. motion-stereo ``D`` to one plane).

    ``steps[j]`` is the change of the range from frame ``j`` to ``j+1`` as odometry
    measures it (e.g. minus the motion along the plane normal), so
    ``TS(j) = D_j + sum_{i >= j} steps[i]``. Returns ``ts`` ``(k, 1)`` and the joint
    covariance (``.dense()`` is ``(k, k)``).
    """
    ranges, variances = np.ravel(ranges).astype(float), np.ravel(variances).astype(float)
    steps, step_variances = np.ravel(steps).astype(float), np.ravel(step_variances).astype(float)
    k = ranges.size
    if variances.size != k or steps.size != k - 1 or step_variances.size != k - 1:
        raise ValueError("need k ranges and variances and k-1 steps and step variances")
    carried = np.concatenate([np.cumsum(steps[::-1])[::-1], [0.0]])
    cov = TrackCovariance(
        meas=variances[:, None, None], h=np.ones((k, 1, 1)), gammas=step_variances[:, None, None]
    )
    return (ranges + carried)[:, None], cov


def to_inverse_range(ts: ArrayLike, cov: TrackCovariance) -> tuple[Array, TrackCovariance]:
    """A range track (:func:`transform_range_track`) in inverse range ``rho = 1 / D``.

    Motion-stereo errors are nearly Gaussian in ``rho`` (linear in pixel and rotation
    errors) and their variance does not grow with ``D``, so fusing there avoids the
    heavy ``1/x`` tail of ``D`` and weights that favour short ranges. First order:
    ``d rho = -d D / D^2`` scales each set's measurement and odometry terms.
    """
    ranges = np.asarray(ts, dtype=float)
    if np.any(ranges <= 0):
        raise ValueError("inverse range needs positive ranges")
    jac = (-1.0 / ranges**2)[:, :, None]  # (k, 1, 1)
    return 1.0 / ranges, TrackCovariance(meas=cov.meas * jac**2, h=cov.h * jac, gammas=cov.gammas)


class STSFTrack:
    """A landmark track for STSF: pose measurements with odometry in between.

    Call :meth:`move` with every odometry increment and :meth:`add` whenever the
    landmark is measured; :meth:`fuse` returns eq. 2 for the latest measured frame.
    With ``max_frames`` only the most recent frames (and increments between them)
    are kept.
    """

    def __init__(self, max_frames: int | None = None) -> None:
        if max_frames is not None and max_frames < 1:
            raise ValueError(f"max_frames must be >= 1, got {max_frames}")
        self.max_frames = max_frames
        self.clear()

    def clear(self) -> None:
        """Forget every frame (e.g. when the landmark is lost)."""
        self._zs, self._covs = np.zeros((0, 3)), np.zeros((0, 3, 3))
        self._us, self._qs = np.zeros((0, 3)), np.zeros((0, 3, 3))
        self._pending, self._pending_cov = np.zeros(3), np.zeros((3, 3))

    def __len__(self) -> int:
        return len(self._zs)

    def move(self, u: ArrayLike, Q: ArrayLike) -> None:
        """Accumulate an odometry increment ``u`` (robot frame) with covariance ``Q``."""
        self._pending, self._pending_cov = compose_gaussian(
            self._pending, self._pending_cov, np.asarray(u, dtype=float), Q
        )

    def add(self, z: ArrayLike, C: ArrayLike) -> None:
        """Add the landmark's pose ``z`` in the current robot frame, covariance ``C``."""
        if len(self):
            self._us = np.vstack([self._us, self._pending[None]])
            self._qs = np.concatenate([self._qs, self._pending_cov[None]])
        self._zs = np.vstack([self._zs, np.reshape(z, (1, 3))])
        self._covs = np.concatenate([self._covs, np.reshape(C, (1, 3, 3))])
        if self.max_frames is not None and len(self) > self.max_frames:
            self._zs, self._covs = self._zs[1:], self._covs[1:]
            self._us, self._qs = self._us[1:], self._qs[1:]
        self._pending, self._pending_cov = np.zeros(3), np.zeros((3, 3))

    def transformed(self) -> tuple[Array, TrackCovariance]:
        """``TS(j)`` of every kept frame and their joint covariance (eq. 3)."""
        if not len(self):
            raise ValueError("the track is empty")
        return transform_pose_track(self._zs, self._covs, self._us, self._qs)

    def fuse(self, method: Method = "significance", gate: float | None = None) -> STSFResult:
        """The landmark's pose in the latest measured frame by STSF, eq. 2-5."""
        ts, cov = self.transformed()
        return stsf_fuse(ts, cov, method=method, angle_index=(2,), gate=gate)
