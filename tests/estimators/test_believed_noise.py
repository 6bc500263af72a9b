"""Believed versus true: the estimators assume their own nominal noise
(``configs/estimators/odometry.yaml``), whatever the env's true noise is, so model mismatch can
be studied; a sweep varies either."""

import pytest
import yaml

from stsf_gym.estimators import estimator_settings
from stsf_gym.experiments.sweep.spec import load_sweep
from stsf_gym.validation import ConfigError
from stsf_gym.wrappers import PoseEstimateWrapper

NOMINAL = estimator_settings("odometry")


@pytest.mark.parametrize("name", ["odometry", "conventional", "stsf", "ekf"])
def test_true_noise_does_not_retune_the_estimators(make_env, name):
    true_noise = {"encoders__radius_error_std": 0.02, "encoders__slip_std": 0.05}
    env = PoseEstimateWrapper(make_env(camera__mode="fast", **true_noise), name)
    env.reset(seed=0)
    noise = env.estimator.model.odometry_noise
    assert noise.radius_var == pytest.approx(NOMINAL.radius_error_std**2)
    assert noise.wheelbase_var == pytest.approx(NOMINAL.wheelbase_error_std**2)
    radius = env.unwrapped.config.robot.wheel_radius
    assert noise.slip_var_per_m == pytest.approx(NOMINAL.slip_std**2 * radius, rel=0.02)


def test_believed_noise_is_an_estimator_option(make_env):
    env = PoseEstimateWrapper(
        make_env(camera__mode="fast"), "ekf", radius_error_std=0.01, principal_point_std_px=2.0
    )
    env.reset(seed=0)
    model = env.estimator.model
    assert model.odometry_noise.radius_var == pytest.approx(1e-4)
    focal = env.unwrapped.camera_calibration.K[0, 0]
    assert model.camera_calibration_std == pytest.approx((2.0 / focal, NOMINAL.focal_std))
    assert env.unwrapped.config.encoders.radius_error_std == NOMINAL.radius_error_std  # truth


def test_nominal_belief_equals_the_default_truth():
    """Nominal values: the defaults of the truth (a mismatch is set on purpose, never by
    accident)."""
    from stsf_gym.envs.config import load_config

    cfg = load_config()
    assert (NOMINAL.slip_std, NOMINAL.radius_error_std, NOMINAL.wheelbase_error_std) == (
        cfg.encoders.slip_std,
        cfg.encoders.radius_error_std,
        cfg.encoders.wheelbase_error_std,
    )
    error = cfg.camera.calibration_error
    assert (NOMINAL.principal_point_std_px, NOMINAL.focal_std) == (
        error.principal_point_std_px,
        error.focal_std,
    )


def test_a_sweep_varies_the_truth_or_the_belief(tmp_path):
    doc = {
        "base": {"world": "straight_10m", "env": {"camera": {"mode": "fast"}}},
        "grid": {"estimator": ["odometry", "ekf"]},
        "one_at_a_time": {
            "env.encoders.radius_error_std": [0.0066],
            "options.radius_error_std": [0.0066, 0.0132],
        },
    }
    path = tmp_path / "mismatch.yaml"
    path.write_text(yaml.safe_dump(doc))
    cells = load_sweep(path).cells
    assert len(cells) == 2 * 3
    truth = [c for c in cells if "env.encoders.radius_error_std" in c["values"]]
    assert all(c["env"]["encoders"]["radius_error_std"] == 0.0066 for c in truth)
    assert all(c["options"]["radius_error_std"] == NOMINAL.radius_error_std for c in truth)
    belief = [c for c in cells if c not in truth]
    assert {c["options"]["radius_error_std"] for c in belief} == {0.0066, 0.0132}
    assert all("encoders" not in c["env"] for c in belief)
    doc["one_at_a_time"] = {"options.radius_error_std": [-1.0]}
    path.write_text(yaml.safe_dump(doc))
    with pytest.raises(
        ConfigError, match=r"options\.radius_error_std.*odometry\.radius_error_std must be >= 0"
    ):
        load_sweep(path)
