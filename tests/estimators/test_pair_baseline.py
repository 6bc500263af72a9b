"""The odometry error of a motion-stereo baseline: slip plus the episode's fixed calibration."""

import numpy as np

from stsf_gym.estimators.landmark_fusion import _Seen
from stsf_gym.estimators.odometry_model import OdometryNoise, integrate_wheel_travel, odometry_step


def test_baseline_error_is_slip_plus_the_calibration_jacobian():
    """Each run draws one radius error per wheel and one wheelbase error (as the env does per
    episode) and slip per step; over a 0.19 m baseline the motion's error must follow
    ``slip_cov + by_calibration Cov(c) by_calibration^T``."""
    wheelbase, samples = 0.3, 4000
    noise = OdometryNoise(2e-6, radius_var=0.0033**2, wheelbase_var=0.01**2)
    travels = [(0.012, 0.0125)] * 10 + [(0.0125, 0.011)] * 6  # 0.19 m with a slight S-bend
    seen = _Seen(observation=None)
    for d in travels:
        u, _, G, G_c = odometry_step(np.zeros(3), *d, wheelbase)
        seen.move(u, G @ np.diag(noise.slip_variances(*d)) @ G.T, G_c)
    rng = np.random.default_rng(1)
    calibration = rng.normal(size=(samples, 3)) * np.sqrt(np.diag(noise.calibration_cov))
    true = np.zeros((samples, 3))
    for d in travels:
        slip = rng.normal(size=(samples, 2)) * np.sqrt(noise.slip_variances(*d))
        rolled = np.array(d) / (1 + calibration[:, :2]) + slip
        bases = wheelbase / (1 + calibration[:, 2])
        true = np.array(
            [integrate_wheel_travel(p, *w, b) for p, w, b in zip(true, rolled, bases, strict=True)]
        )
    errors = seen.motion - true
    cov = seen.slip_cov + seen.by_calibration @ noise.calibration_cov @ seen.by_calibration.T
    nees = np.einsum("ni,ij,nj->n", errors, np.linalg.inv(cov), errors).mean()
    assert abs(nees - 3.0) < 0.25
    # the calibration part, signs included: the errors regressed on each run's c, within four
    # standard errors of the fit (slip is the residual) and 5 % for the first-order model
    fitted = np.linalg.lstsq(calibration, errors, rcond=None)[0].T
    residual_std = (errors - calibration @ fitted.T).std(axis=0)
    standard_error = np.outer(residual_std, 1 / (calibration.std(axis=0) * np.sqrt(samples)))
    bound = 4 * standard_error + 0.05 * np.abs(seen.by_calibration)
    assert np.all(np.abs(fitted - seen.by_calibration) < bound)
