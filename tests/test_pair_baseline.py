"""The odometry covariance of a motion-stereo baseline: slip plus a systematic wheel scale."""

import numpy as np

from stsf_gym.estimators.landmark_fusion import _Seen
from stsf_gym.estimators.odometry import OdometryNoise, integrate_wheel_travel, odometry_step


def test_baseline_covariance_matches_a_fixed_wheel_scale_error():
    """Each run draws one radius error per wheel (as the env does per episode) and slip per
    step. The baseline covariance describes the spread of the odometry's error over 0.19 m; the
    random walk matched at 5 m (the estimator's prediction noise) overstates it many times."""
    wheelbase, samples, radius_std = 0.3, 4000, 0.0033
    slip_noise = OdometryNoise(2e-6)
    scale_noise = OdometryNoise(0.0, radius_std**2, calibration_length=1.0)
    walk_noise = OdometryNoise(2e-6, radius_std**2, calibration_length=5.0)
    travels = [(0.012, 0.0125)] * 10 + [(0.0125, 0.011)] * 6  # 0.19 m with a slight S-bend
    seen, walk_cov = _Seen(observation=None), np.zeros((3, 3))
    for d in travels:
        _, F, Q = odometry_step(seen.motion, *d, wheelbase, walk_noise)
        walk_cov = F @ walk_cov @ F.T + Q
        u = odometry_step(np.zeros(3), *d, wheelbase, walk_noise)[0]
        q_slip, q_scale = (
            odometry_step(np.zeros(3), *d, wheelbase, n)[2] for n in (slip_noise, scale_noise)
        )
        seen.move(u, q_slip, q_scale)
    rng = np.random.default_rng(1)
    scales = 1 + rng.normal(0, radius_std, (samples, 2))
    true = np.zeros((samples, 3))
    for d in travels:
        slip = rng.normal(0, 1, (samples, 2)) * np.sqrt(slip_noise.wheel_variances(*d))
        rolled = np.array(d) * scales + slip
        true = np.array(
            [integrate_wheel_travel(p, *w, wheelbase) for p, w in zip(true, rolled, strict=True)]
        )
    errors = true - seen.motion

    def nees(cov):
        return np.einsum("ni,ij,nj->n", errors, np.linalg.inv(cov), errors).mean()

    # first order a fixed scale's sideways drift grows like d^2 / 2, the random walk matched at
    # the baseline like d^1.5 / sqrt(3): its variance is up to 4/3 too wide, never too narrow
    assert 3.0 / (4 / 3) - 0.1 < nees(seen.motion_cov) < 3.3
    assert nees(walk_cov) < 0.5
