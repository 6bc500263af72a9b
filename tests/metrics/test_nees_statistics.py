"""NEES consistency over time: a time-averaged NEES judged against bounds of its own degrees
of freedom, the correlation of the steps acknowledged (integrated autocorrelation time)."""

import numpy as np
import pytest

from stsf_gym.metrics import autocorrelation_time, chi2_bounds, time_averaged_nees_bounds


def _correlated_errors(rng, runs, steps, phi, dim=3):
    """Unit-variance AR(1) errors: a consistent estimator whose error persists over steps."""
    errors = np.empty((runs, steps, dim))
    errors[:, 0] = rng.standard_normal((runs, dim))
    for k in range(1, steps):
        errors[:, k] = phi * errors[:, k - 1] + np.sqrt(1 - phi**2) * rng.standard_normal(
            (runs, dim)
        )
    return errors


def test_autocorrelation_time_of_white_and_ar1_series():
    rng = np.random.default_rng(0)
    assert autocorrelation_time(rng.standard_normal(20000)) == pytest.approx(1.0, abs=0.1)
    ar = _correlated_errors(rng, 1, 40000, 0.9, dim=1)[0, :, 0]
    assert autocorrelation_time(ar) == pytest.approx((1 + 0.9) / (1 - 0.9), rel=0.25)
    assert autocorrelation_time(np.ones(5)) == 1.0


def test_time_averaged_nees_judged_with_the_steps_correlation():
    """Consistent but correlated runs: their time-averaged NEES is inside its own bounds about
    95 % of the time (bounds taking every step as independent would reject it most times); a
    covariance 1.7 times too large is caught below the bounds."""
    rng = np.random.default_rng(1)
    runs, steps, inside, naive_inside, pessimistic_caught = 10, 400, 0, 0, 0
    trials = 100
    for _ in range(trials):
        errors = _correlated_errors(rng, runs, steps, 0.95)
        trace = np.mean(np.sum(errors**2, axis=2), axis=0)  # identity covariance
        average, (low, high), effective = time_averaged_nees_bounds(trace, 3, runs)
        assert 1 <= effective < steps
        inside += low <= average <= high
        naive_low, naive_high = chi2_bounds(3, runs * steps)
        naive_inside += naive_low <= average <= naive_high
        average, (low, _), _ = time_averaged_nees_bounds(trace / 1.7, 3, runs)
        pessimistic_caught += average < low
    assert inside / trials >= 0.85
    assert naive_inside / trials < 0.6
    assert pessimistic_caught / trials >= 0.9
