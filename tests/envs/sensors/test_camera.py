import math
import os

import cv2
import numpy as np
import pytest

from stsf_gym.experiments.detector_views import detection_records, room_world, summarise_records

VIEWS = [  # (world, start pose, pan in degrees): frontal, oblique, panned, near and far
    ("stsf_gym/Straight10m-v0", [8.5, 0.2, 0.05], 0.0),
    ("stsf_gym/Straight10m-v0", [6.0, -0.6, 0.6], 0.0),
    ("stsf_gym/Corridor-v0", [2.0, -0.3, 0.0], 45.0),
    ("stsf_gym/Straight10m-v0", [9.3, 0.0, 0.0], 0.0),
    ("stsf_gym/Straight10m-v0", [4.0, 0.1, 0.0], 0.0),
]
NOISELESS = {  # the paper's lens (distortion, vignetting, defocus), no sensor noise
    "camera__sensor__read_noise": 0.0,
    "camera__sensor__shot_noise": 0.0,
    "camera__sensor__gain_std": 0.0,
}


def square_blobs(image: np.ndarray, board: np.ndarray) -> np.ndarray:
    """Intensity-weighted centroids of the bright squares inside a board's image polygon."""
    grey = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY).astype(float)
    mask = np.zeros(grey.shape, np.uint8)
    cv2.fillConvexPoly(mask, np.round(board).astype(np.int32), 1)
    mask = cv2.erode(mask, np.ones((5, 5), np.uint8))  # keep off the board's blurred edge
    inside = grey[mask > 0]
    threshold = (inside.min() + inside.max()) / 2
    count, labels = cv2.connectedComponents(((grey > threshold) & (mask > 0)).astype(np.uint8))
    centres = []
    for label in range(1, count):
        rows, cols = np.nonzero(labels == label)
        weights = grey[rows, cols] - threshold
        centres.append([cols @ weights / weights.sum(), rows @ weights / weights.sum()])
    return np.array(centres).reshape(-1, 2)


@pytest.mark.slow
@pytest.mark.parametrize("renderer", ["gl", "egl", "tiny"])
@pytest.mark.parametrize(("env_id", "start", "pan_deg"), VIEWS)
def test_squares_within_a_pixel_of_true_camera_projection(
    make_env, renderer, env_id, start, pan_deg
):
    """Square centres in the frame lie where cv2.projectPoints puts them with the TRUE K and
    distortion and ``info["camera_pose"]``."""
    env = make_env(
        env_id,
        camera__renderer=renderer,
        camera__width=640,
        camera__height=480,
        camera__pan_deg=pan_deg,
        **NOISELESS,
    )
    obs, info = env.reset(seed=0, options={"start_pose": start})
    unwrapped = env.unwrapped
    if renderer == "tiny":
        assert unwrapped.renderer == "tiny"
    visible = unwrapped.landmarks_in_view(info["camera_pose"])
    assert visible, "the view must contain a landmark"
    assert np.any(unwrapped.dist_coeffs != 0), "the test must see a distorting lens"
    camera_from_world = np.linalg.inv(info["camera_pose"])
    rvec = cv2.Rodrigues(camera_from_world[:3, :3])[0]

    def project(points: np.ndarray) -> np.ndarray:
        uv, _ = cv2.projectPoints(
            points, rvec, camera_from_world[:3, 3], unwrapped.camera_matrix, unwrapped.dist_coeffs
        )
        return uv.reshape(-1, 2)

    errors = []
    for landmark in (lm for lm in unwrapped.landmarks if lm.id in visible):
        blobs = square_blobs(obs["image"], project(landmark.board_corners))
        assert len(blobs) == len(landmark.square_centres)
        for point in project(landmark.square_centres):
            errors.append(np.min(np.linalg.norm(blobs - point, axis=1)))
    errors = np.array(errors)
    assert len(errors) >= 17
    assert np.max(errors) < 1.0, f"{unwrapped.renderer}: errors {np.round(errors, 2)}"


def test_camera_matrix_matches_projection_and_image(make_env):
    env = make_env(camera__width=320, camera__height=240, camera__vfov_deg=45.0)
    K = env.unwrapped.camera_matrix
    obs, _ = env.reset(seed=0)
    assert obs["image"].shape == (240, 320, 3) and obs["image"].dtype == np.uint8
    f = 120 / math.tan(math.radians(22.5))
    np.testing.assert_allclose(K, [[f, 0, 159.5], [0, f, 119.5], [0, 0, 1]])


def test_camera_pose_is_opencv_axes(make_env):
    env = make_env(camera__enabled=False)
    _, info = env.reset(seed=0, options={"start_pose": [1.0, 0.0, math.pi / 2]})
    pose = info["camera_pose"]
    np.testing.assert_allclose(pose[:3, 2], [0, 1, 0], atol=1e-3)  # z forward: the robot's heading
    np.testing.assert_allclose(pose[:3, 1], [0, 0, -1], atol=1e-3)  # y down
    np.testing.assert_allclose(pose[:3, 0], [1, 0, 0], atol=1e-3)  # x right
    cfg = env.unwrapped.config.robot
    np.testing.assert_allclose(pose[:3, 3], [1.0, cfg.camera_forward, cfg.camera_height], atol=2e-3)
    nominal = env.unwrapped.robot_from_camera(0.0, 0.0)
    np.testing.assert_allclose(nominal[:3, 3], [cfg.camera_forward, 0.0, cfg.camera_height])


def test_frames_at_camera_rate_not_control_rate(make_env):
    env = make_env(camera__rate_hz=5.0)  # control at 10 Hz
    obs, _ = env.reset(seed=0)
    flags = [obs["image_new"]]
    for _ in range(10):
        obs, *_ = env.step(np.float32([0.5, 0.0]))
        flags.append(obs["image_new"])
    assert flags == [1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1]


def test_gl_renderer_used_when_expected(make_env):
    """CI installs Mesa's EGL and sets STSF_EXPECT_EGL=1, so the GL path is the one tested."""
    env = make_env()
    assert env.unwrapped.renderer in ("gl", "egl", "tiny")
    if os.environ.get("STSF_EXPECT_EGL") == "1":
        assert env.unwrapped.renderer == "gl"


@pytest.mark.slow
@pytest.mark.parametrize("profile", ["paper", "ideal"])
def test_feature_error_matches_the_profile(make_env, profile):
    """The detector's square centres, as the estimators see them (undistorted with the
    episode's believed calibration), err by the profile's ``feature_rms_px`` within 20 %; the
    ideal camera stays under 0.1 px. Each view is a new episode: a new calibration draw."""
    env = make_env("stsf_gym/Straight10m-v0", world=room_world(), camera__profile=profile)
    records = detection_records(env, np.random.default_rng(3), repeats=2)  # 1-8 m, 0-60 deg
    summary = summarise_records(records)
    assert summary["detection_rate"] > 0.5
    target = env.unwrapped.config.camera.feature_rms_px
    assert summary["calibrated_feature_rms_px"] == pytest.approx(target, rel=0.2)
    if profile == "ideal":
        assert summary["calibrated_feature_rms_px"] < 0.1
    else:  # the sensor's own part is a fraction of it: the calibration error is felt
        assert summary["feature_rms_px"] < 0.5 * summary["calibrated_feature_rms_px"]


def test_calibration_drawn_per_episode_and_distinct_from_truth(make_env):
    env = make_env(camera__mode="fast")
    u = env.unwrapped
    env.reset(seed=1)
    first = u.camera_calibration
    env.reset(seed=1)
    assert np.array_equal(u.camera_calibration.K, first.K)
    assert np.array_equal(u.camera_calibration.dist, first.dist)
    env.reset(seed=2)
    assert not np.array_equal(u.camera_calibration.K, first.K)
    assert not np.array_equal(first.K, u.camera_matrix)
    assert not np.array_equal(first.dist, u.dist_coeffs)
    ideal = make_env(camera__mode="fast", camera__profile="ideal")
    ideal.reset(seed=1)
    u = ideal.unwrapped
    np.testing.assert_array_equal(u.camera_calibration.K, u.camera_matrix)
