"""The ``degraded-truth`` dial: its errors, its seeding, and a covariance consistent with them."""

from __future__ import annotations

import numpy as np
import pytest

from stsf_gym.estimators import make_estimator
from stsf_gym.estimators.degraded_truth import DegradedTruth
from stsf_gym.metrics import chi2_bounds, fraction_inside, nees, pose_error

DT = 0.1
#: No error of any kind: each test sets the errors it studies.
NONE = {
    "noise_std": [0.0, 0.0],
    "bias_std": [0.0, 0.0],
    "drift_std": [0.0, 0.0],
    "rate_hz": None,
    "latency_s": 0.0,
    "dropout_probability": 0.0,
    "scale": 1.0,
}


def dial(**options) -> DegradedTruth:
    """A degraded-truth source with only ``options``' errors."""
    return make_estimator("degraded-truth", **{**NONE, **options})


def drive(source: DegradedTruth, seed: int, steps: int = 300, velocity=(0.12, 0.0, 0.05)):
    """Move at a constant world ``velocity`` (m/s, m/s, rad/s); the source's errors,
    covariances and means at every step."""
    source.seed(seed)
    start = np.zeros(3)
    source.reset(None, start, np.diag([1e-4, 1e-4, 1e-5]))
    source.see(start)
    errors, covs, means = [], [], []
    for k in range(1, steps + 1):
        pose = k * DT * np.asarray(velocity, dtype=float)
        source.see(pose)
        mean, cov = source.update({}, DT)
        errors.append(pose_error(mean, pose))
        covs.append(cov)
        means.append(mean.copy())
    return np.array(errors), np.array(covs), np.array(means)


def monte_carlo_nees(runs: int = 40, speeds=None, **options) -> tuple[np.ndarray, tuple]:
    """The NEES averaged over ``runs`` seeds at every step, and its 95 % bounds."""
    values = []
    for seed in range(runs):
        velocity = (0.12, 0.0, 0.05) if speeds is None else speeds(seed)
        errors, covs, _ = drive(dial(**options), seed, velocity=velocity)
        values.append(nees(errors, covs))
    return np.mean(values, axis=0), chi2_bounds(3, runs)


@pytest.mark.slow
def test_white_bias_and_drift_are_consistent():
    average, bounds = monte_carlo_nees(
        noise_std=(0.05, 0.02), bias_std=(0.03, 0.01), drift_std=(0.05, 0.01)
    )
    assert fraction_inside(average, bounds) >= 0.9
    assert bounds[0] < np.mean(average) < bounds[1]


@pytest.mark.slow
def test_rate_latency_and_dropouts_are_consistent_for_motion_within_the_model():
    """With hold, latency and dropouts the covariance adds the motion since the measured
    instant as a velocity of std ``motion_std`` per axis: consistent when it is that."""
    motion = (0.2, 0.1)

    def speeds(seed):
        rng = np.random.default_rng(1000 + seed)
        return rng.normal(0.0, [motion[0], motion[0], motion[1]])

    average, bounds = monte_carlo_nees(
        runs=60,
        speeds=speeds,
        noise_std=(0.02, 0.01),
        rate_hz=2.0,
        latency_s=0.3,
        dropout_probability=0.2,
        motion_std=motion,
    )
    assert fraction_inside(average, bounds) >= 0.85


def test_an_understated_covariance_is_caught():
    """The test above can fail: report half the noise it adds and the NEES leaves its bounds."""
    source = dial(noise_std=(0.05, 0.02))
    errors, covs, _ = drive(source, 0)
    assert np.mean(nees(errors, covs / 4)) > chi2_bounds(3)[1]


def test_error_sizes_follow_the_model():
    errors, _, _ = drive(dial(noise_std=(0.05, 0.02)), 1, steps=2000)
    assert np.std(errors[:, 0]) == pytest.approx(0.05, rel=0.1)
    assert np.std(errors[:, 2]) == pytest.approx(0.02, rel=0.1)
    scaled, _, _ = drive(dial(noise_std=(0.05, 0.02), scale=3.0), 1, steps=2000)
    np.testing.assert_allclose(scaled, 3 * errors, atol=1e-9)  # the dial scales the same draws
    _, _, held = drive(dial(noise_std=(0.05, 0.02), rate_hz=1.0), 1, steps=50)
    assert len(np.unique(held[:, 0])) == 6  # at the first step, then at t = 1, 2, ... 5 s
    _, _, late = drive(dial(scale=0.0, latency_s=0.5), 1, steps=50)
    np.testing.assert_allclose(late[10:, 0], 0.12 * DT * (np.arange(11, 51) - 5), atol=1e-12)


def test_same_seed_same_errors_and_zero_dial_is_truth():
    a, _, _ = drive(dial(bias_std=(0.1, 0.0), drift_std=(0.05, 0.0)), 7)
    b, _, _ = drive(dial(bias_std=(0.1, 0.0), drift_std=(0.05, 0.0)), 7)
    c, _, _ = drive(dial(bias_std=(0.1, 0.0), drift_std=(0.05, 0.0)), 8)
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)
    zero, covs, _ = drive(dial(scale=0.0), 7)
    np.testing.assert_allclose(zero, 0.0, atol=1e-12)
    assert np.all(np.linalg.eigvalsh(covs) > 0)


def test_options_come_from_the_yaml_file_and_bad_values_are_named():
    source = make_estimator("degraded-truth")
    assert source.noise[0] > 0  # configs/estimators/degraded-truth.yaml
    with pytest.raises(ValueError, match=r"degraded-truth\.noise_std\[0\] must be >= 0"):
        dial(noise_std=(-1.0, 0.0))
    with pytest.raises(ValueError, match=r"degraded-truth\.dropout_probability"):
        dial(dropout_probability=1.0)
    with pytest.raises(ValueError, match=r"degraded-truth\.rate_hz"):
        dial(rate_hz=0)
    with pytest.raises(ValueError, match=r"degraded-truth\.nosie"):
        make_estimator("degraded-truth", nosie=1.0)


@pytest.mark.slow
def test_in_the_env_it_is_seeded_and_consistent():
    """The wrapper's source, driven by the follower: the same seed gives the same estimates,
    and over 10 seeds the Monte-Carlo NEES (3 dof) stays inside its 95 % bounds."""
    from stsf_gym.experiments.episodes import EpisodeSpec, run_episode
    from stsf_gym.experiments.statistics import nees_consistency

    env = {"camera": {"enabled": False}, "sim": {"max_episode_seconds": 15.0}}
    episodes = [
        run_episode(EpisodeSpec("straight_10m", "degraded-truth", s, env=env)) for s in range(10)
    ]
    again = run_episode(EpisodeSpec("straight_10m", "degraded-truth", 0, env=env))
    assert again.estimates == episodes[0].estimates
    assert episodes[1].estimates != episodes[0].estimates
    inside, (low, high) = nees_consistency(episodes)
    assert low < np.mean([e.nees for e in episodes]) < high
    assert inside >= 0.9
