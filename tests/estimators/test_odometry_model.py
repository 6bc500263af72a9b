import numpy as np
import pytest

from stsf_gym.camera_model import CameraCalibration
from stsf_gym.estimators import SensorModel, make_estimator
from stsf_gym.estimators.odometry_model import OdometryNoise, integrate_wheel_travel
from stsf_gym.geometry import OdometryCalibration
from stsf_gym.vision.landmarks import LandmarkPattern


def test_straight_and_turn_in_place():
    pose = integrate_wheel_travel(np.zeros(3), 1.0, 1.0, 0.4)
    np.testing.assert_allclose(pose, [1.0, 0.0, 0.0])
    pose = integrate_wheel_travel(np.zeros(3), -0.1 * np.pi, 0.1 * np.pi, 0.4)
    np.testing.assert_allclose(pose, [0.0, 0.0, np.pi / 2], atol=1e-12)


@pytest.mark.slow
def test_dead_reckoning_covariance_matches_monte_carlo():
    """The odometry estimator's covariance (slip as a random walk, the calibration errors fixed
    per run) against sampled runs with both: the NEES averages the state dimension (3)."""
    ticks_per_rev, radius, wheelbase = 2000, 0.05, 0.4
    noise = OdometryNoise(slip_var_per_m=2e-5, radius_var=1e-4, wheelbase_var=1e-4)
    calibration = OdometryCalibration(ticks_per_rev, radius, radius, wheelbase)
    model = SensorModel(
        calibration=calibration,
        odometry_noise=noise,
        camera_calibration=CameraCalibration(np.eye(3), np.zeros(5)),
        camera_calibration_std=(0.0, 0.0),
        camera_matrix=np.eye(3),
        image_size=(1, 1),
        robot_from_camera=lambda pan, tilt: np.eye(4),
        landmarks={},
        pattern=LandmarkPattern(),
        walls=np.zeros((0, 4)),
    )
    estimator = make_estimator("odometry")
    estimator.reset(model, np.zeros(3), np.zeros((3, 3)))
    ticks = [(40, 40)] * 80 + [(25, 50)] * 40 + [(48, 32)] * 60
    for step in ticks:
        mean, cov = estimator.update({"encoders": np.array(step)}, 0.1)
    rng = np.random.default_rng(0)
    c = rng.standard_normal((2000, 3)) * np.sqrt(np.diag(noise.calibration_cov))
    samples = np.zeros((len(c), 3))
    for step in ticks:
        nominal = calibration.wheel_travel(step)
        travel = nominal * (1 + c[:, :2])  # radii (1 + c) off
        travel += rng.standard_normal(travel.shape) * np.sqrt(noise.slip_variances(*nominal))
        true_wheelbase = wheelbase / (1 + c[:, 2])  # believed 1 + c too large
        samples = np.array(
            [
                integrate_wheel_travel(p, *d, b)
                for p, d, b in zip(samples, travel, true_wheelbase, strict=True)
            ]
        )
    np.testing.assert_allclose(mean, integrate_wheel_travel_all(ticks, calibration), atol=1e-12)
    errors = samples - mean
    nees = np.einsum("ni,ij,nj->n", errors, np.linalg.inv(cov), errors)
    assert nees.mean() == pytest.approx(3.0, rel=0.1)
    assert np.all(np.abs(errors.mean(axis=0)) < 4 * np.sqrt(np.diag(cov) / len(samples)))


def integrate_wheel_travel_all(ticks, calibration: OdometryCalibration) -> np.ndarray:
    pose = np.zeros(3)
    for step in ticks:
        pose = integrate_wheel_travel(pose, *calibration.wheel_travel(step), calibration.wheelbase)
    return pose


def test_slip_cov_is_the_diagonal_of_the_slip_variances_to_the_bit():
    noise = OdometryNoise.from_encoders(0.02, 0.003, 0.004, 0.05)
    rng = np.random.default_rng(0)
    for d_left, d_right in [*rng.normal(0, 0.05, (50, 2)).tolist(), (0.0, -0.0)]:
        expected = np.diag(noise.slip_variances(d_left, d_right))
        assert noise.slip_cov(d_left, d_right).tobytes() == expected.tobytes()
    with pytest.raises(ValueError):  # made once and shared: nobody may write into it
        noise.calibration_cov[0, 0] = 1.0
