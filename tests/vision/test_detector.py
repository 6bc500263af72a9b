"""Landmark detector (paper sect. 3.1): ids and sub-pixel square centres on rendered frames."""

from __future__ import annotations

import dataclasses
import math

import cv2
import gymnasium as gym
import numpy as np
import pytest

import stsf_gym  # noqa: F401 - registers the ids
from stsf_gym.vision.board import GROW, BoardFit, _window_centroids
from stsf_gym.vision.detector import Detection, LandmarkDetector
from stsf_gym.vision.landmarks import LandmarkPattern, landmark_image, lit_cells, square_centres
from stsf_gym.vision.ncc import MIN_WINDOW_STD, CorrelationTemplate, correlate

PATTERN = LandmarkPattern()
CAMERA_FORWARD = 0.10  # robot.camera_forward in configs/default.yaml: optical centre ahead of axle


@pytest.fixture(scope="module")
def detector():
    return LandmarkDetector(PATTERN)


@pytest.fixture(scope="module")
def corridor():
    env = gym.make("stsf_gym/Straight10m-v0")
    yield env
    env.close()


@pytest.fixture(scope="module")
def panned():
    env = gym.make("stsf_gym/Straight10m-v0", camera__pan_deg=90.0)
    yield env
    env.close()


def robot_pose_looking_at(target_xy, distance, bearing_deg):
    """Robot [x, y, yaw] whose camera sits ``distance`` from ``target_xy`` looking at it.

    ``bearing_deg`` is the world direction from the camera to the target.
    """
    b = math.radians(bearing_deg)
    cam = np.asarray(target_xy) - distance * np.array([math.cos(b), math.sin(b)])
    axle = cam - CAMERA_FORWARD * np.array([math.cos(b), math.sin(b)])
    return [float(axle[0]), float(axle[1]), b]


def render(env, pose):
    obs, info = env.reset(seed=0, options={"start_pose": pose})
    return obs["image"], info["camera_pose"]


def truth_pixels(env, camera_pose, landmark_id):
    landmark = next(lm for lm in env.unwrapped.landmarks if lm.id == landmark_id)
    return env.unwrapped.camera.project(camera_pose, landmark.square_centres)


def check_detection(env, image, camera_pose, detector, expected_id):
    assert expected_id in env.unwrapped.landmarks_in_view(camera_pose)
    detections = detector.detect(image)
    assert [d.landmark_id for d in detections] == [expected_id]
    det = detections[0]
    truth = truth_pixels(env, camera_pose, expected_id)
    assert len(det.indices) == len(truth)  # every lit square found
    err = np.linalg.norm(det.image_points - truth[det.indices], axis=1)
    assert err.max() < 1.0, err
    assert np.median(err) < 0.35, err
    return det, err


@pytest.mark.parametrize("distance", [2.0, 3.5, 5.0])
def test_frontal_end_wall(corridor, detector, distance):
    # Landmark 4 hangs on the end wall at x = 11.5 facing -x.
    image, pose = render(corridor, robot_pose_looking_at([11.44, 0.0], distance, 0.0))
    check_detection(corridor, image, pose, detector, 4)


def test_oblique_45_degrees(corridor, detector):
    # Landmark 1 on the left wall at (2.5, 1.2) facing -y, seen 45 degrees off its normal.
    image, pose = render(corridor, robot_pose_looking_at([2.5, 1.14], 1.5, 45.0))
    det, _ = check_detection(corridor, image, pose, detector, 1)
    # Foreshortened: the board is markedly narrower than tall in the image.
    width = np.ptp(det.corners[:, 0])
    height = np.ptp(det.corners[:, 1])
    assert width < 0.85 * height


def test_panned_camera(panned, detector):
    # Robot heading +x, camera panned 90 degrees left onto landmark 3 at (7.5, 1.2).
    image, pose = render(panned, [7.5, -0.2, 0.0])
    forward = pose[:3, 2]
    assert forward[1] > 0.95  # the camera does look along +y
    check_detection(panned, image, pose, detector, 3)


@pytest.mark.parametrize("pose", [[1.5, 0.0, math.pi], [3.5, 0.0, -math.pi / 2], [1.0, 0.0, 2.5]])
def test_no_landmark_in_view_gives_no_detection(corridor, detector, pose):
    image, camera_pose = render(corridor, pose)
    assert corridor.unwrapped.landmarks_in_view(camera_pose) == []
    assert detector.detect(image) == []


def test_detection_fields_and_grey_input(corridor, detector):
    image, _ = render(corridor, robot_pose_looking_at([11.44, 0.0], 3.0, 0.0))
    (det,) = detector.detect(image)
    assert isinstance(det, Detection)
    n = len(lit_cells(det.landmark_id, PATTERN))
    assert det.image_points.shape == (n, 2) and det.image_points.dtype == np.float64
    np.testing.assert_array_equal(det.indices, np.arange(n))
    np.testing.assert_allclose(
        det.plane_points, square_centres(det.landmark_id, PATTERN)[det.indices]
    )
    assert det.homography.shape == (3, 3)
    assert 0.0 < det.score <= 1.0
    assert det.reprojection_rms < 0.5
    np.testing.assert_allclose(det.project(det.plane_points), det.image_points, atol=1.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        det.landmark_id = 3  # type: ignore[misc]
    grey = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
    (det_grey,) = detector.detect(grey)
    np.testing.assert_allclose(det_grey.image_points, det.image_points, atol=1e-9)


# --- synthetic images ----------------------------------------------------------------------
PX_PER_M = 400.0


def plane_to_texture(pattern: LandmarkPattern, px_per_m: float) -> np.ndarray:
    """3x3 map from landmark-plane metres to landmark_image pixels (pixel centres at integers)."""
    n = round(pattern.size * px_per_m)
    s = n / pattern.size
    return np.array([[s, 0.0, n / 2 - 0.5], [0.0, -s, n / 2 - 0.5], [0.0, 0.0, 1.0]])


def paste(canvas, landmark_id, quad):
    """Warp landmark ``landmark_id`` onto ``canvas`` so its board corners land on ``quad``.

    Returns the homography from landmark-plane metres to canvas pixels.
    """
    tex = landmark_image(landmark_id, PATTERN, PX_PER_M)
    n = tex.shape[0]
    src = np.array([[-0.5, -0.5], [n - 0.5, -0.5], [n - 0.5, n - 0.5], [-0.5, n - 0.5]])
    tex_to_img = cv2.getPerspectiveTransform(src.astype(np.float32), np.float32(quad))
    h, w = canvas.shape
    # Supersample 4x and box-filter down: an anti-aliased "camera" image of the board.
    up = np.array([[4.0, 0, 1.5], [0, 4.0, 1.5], [0, 0, 1]])
    big = cv2.warpPerspective(tex, up @ tex_to_img, (4 * w, 4 * h), flags=cv2.INTER_LINEAR)
    inside = cv2.warpPerspective(np.ones_like(tex), up @ tex_to_img, (4 * w, 4 * h))
    board = cv2.resize(big.astype(np.float32), (w, h), interpolation=cv2.INTER_AREA)
    cover = cv2.resize(inside.astype(np.float32), (w, h), interpolation=cv2.INTER_AREA)
    canvas[:] = cover * board * 0.85 + (1 - cover) * canvas
    return tex_to_img @ plane_to_texture(PATTERN, PX_PER_M)


def noisy_wall(shape, seed):
    rng = np.random.default_rng(seed)
    h, w = shape
    ramp = np.linspace(120, 190, w)[None, :] + np.linspace(-15, 15, h)[:, None]
    return ramp + rng.normal(0, 3.0, shape)


def project(h, xy):
    p = xy @ h[:, :2].T + h[:, 2]
    return p[:, :2] / p[:, 2:]


def finish(canvas, seed):
    rng = np.random.default_rng(seed)
    return np.clip(canvas + rng.normal(0, 2.0, canvas.shape), 0, 255).round().astype(np.uint8)


@pytest.mark.parametrize(
    ("landmark_id", "quad"),
    [
        (123, [[100, 60], [200, 64], [196, 165], [98, 160]]),  # near frontal, slight roll
        (37, [[120, 50], [190, 70], [190, 150], [120, 175]]),  # oblique: right side further
        (255, [[150, 100], [180, 100], [180, 130], [150, 130]]),  # small (30 px board)
    ],
)
def test_synthetic_warped_landmark(detector, landmark_id, quad):
    canvas = noisy_wall((240, 320), seed=landmark_id)
    hom = paste(canvas, landmark_id, quad)
    image = finish(canvas, seed=1)
    detections = detector.detect(image)
    assert [d.landmark_id for d in detections] == [landmark_id]
    det = detections[0]
    truth = project(hom, square_centres(landmark_id, PATTERN))
    assert len(det.indices) == len(truth)
    err = np.linalg.norm(det.image_points - truth[det.indices], axis=1)
    assert err.max() < 0.5, err
    assert np.median(err) < 0.2, err


def test_two_landmarks_in_one_frame(detector):
    canvas = noisy_wall((240, 320), seed=7)
    homs = {
        5: paste(canvas, 5, [[30, 60], [130, 60], [130, 160], [30, 160]]),
        200: paste(canvas, 200, [[190, 80], [270, 85], [268, 165], [190, 162]]),
    }
    image = finish(canvas, seed=2)
    detections = detector.detect(image)
    assert sorted(d.landmark_id for d in detections) == [5, 200]
    for det in detections:
        truth = project(homs[det.landmark_id], det.plane_points)
        assert np.linalg.norm(det.image_points - truth, axis=1).max() < 0.5
    # valid_ids drops ids the world does not have
    only = LandmarkDetector(PATTERN, valid_ids={200}).detect(image)
    assert [d.landmark_id for d in only] == [200]


@pytest.mark.parametrize("seed", range(3))
def test_noise_and_clutter_give_no_detection(detector, seed):
    rng = np.random.default_rng(seed)
    canvas = noisy_wall((240, 320), seed)
    # Dark rectangles and a grid of light dots without the ring: not landmarks.
    for _ in range(6):
        x, y = rng.integers(0, 280), rng.integers(0, 200)
        w, h = rng.integers(15, 60, size=2)
        canvas[y : y + h, x : x + w] = rng.uniform(0, 40)
    canvas[100:160, 100:160] = 5
    for r in range(4):
        for c in range(4):
            canvas[106 + 14 * r : 112 + 14 * r, 106 + 14 * c : 112 + 14 * c] = 200
    assert detector.detect(finish(canvas, seed)) == []


def test_bad_input(detector):
    with pytest.raises(TypeError):
        detector.detect(np.zeros((240, 320), np.float32))
    with pytest.raises(ValueError):
        detector.detect(np.zeros((240, 320, 2), np.uint8))
    assert detector.detect(np.zeros((240, 320), np.uint8)) == []
    assert detector.detect(np.zeros((5, 5), np.uint8)) == []


def test_detect_is_stateless(detector):
    canvas = noisy_wall((240, 320), seed=11)
    paste(canvas, 42, [[110, 70], [190, 72], [188, 150], [108, 148]])
    with_board = finish(canvas, seed=3)
    without = finish(noisy_wall((240, 320), seed=12), seed=4)
    first = detector.detect(with_board)
    detector.detect(without)
    again = detector.detect(with_board)
    assert [d.landmark_id for d in first] == [42]
    assert [d.landmark_id for d in again] == [42]
    np.testing.assert_array_equal(again[0].image_points, first[0].image_points)


@pytest.mark.parametrize("shape", [(239, 321), (481, 641)])
def test_odd_image_sizes(detector, shape):
    # Odd sides exercise the pyramid's dropped rows and columns; points stay in full pixels.
    h, w = shape
    cx, cy, half = w / 2, h / 2, 0.2 * h
    quad = [[cx - half, cy - half], [cx + half, cy - half], [cx + half, cy + half]]
    quad.append([cx - half, cy + half])
    canvas = noisy_wall(shape, seed=5)
    hom = paste(canvas, 99, quad)
    (det,) = detector.detect(finish(canvas, seed=6))
    assert det.landmark_id == 99
    truth = project(hom, det.plane_points)
    assert np.linalg.norm(det.image_points - truth, axis=1).max() < 0.5


def test_window_centroids_match_a_loop_over_windows():
    rng = np.random.default_rng(0)
    weight = rng.uniform(0, 50, (40, 60)).astype(np.float32)
    weight[rng.uniform(size=weight.shape) < 0.3] = 0
    boxes = np.array([[0, 0, 5, 4], [20, 10, 6, 6], [55, 35, 5, 5], [30, 5, 1, 1]])
    weight[4:7, 29:32] = 0  # the last window (grown by 1) has no weight: its fallback is kept
    fallback = rng.uniform(0, 40, (len(boxes), 2))
    got = _window_centroids(weight, boxes, 1, fallback)
    ys, xs = np.mgrid[0:40, 0:60]
    for (x, y, w, h), point, back in zip(boxes, got, fallback, strict=True):
        win = np.s_[max(y - 1, 0) : y + h + 1, max(x - 1, 0) : x + w + 1]
        total = weight[win].sum(dtype=np.float64)
        if total == 0:
            np.testing.assert_array_equal(point, back)
            continue
        expected = [(weight[win] * xs[win]).sum() / total, (weight[win] * ys[win]).sum() / total]
        np.testing.assert_allclose(point, expected, atol=1e-6)


def test_board_fitter_grows_when_the_region_cuts_the_board():
    canvas = noisy_wall((240, 320), seed=8)
    hom = paste(canvas, 7, [[100, 60], [200, 60], [200, 160], [100, 160]])
    grey = finish(canvas, seed=9)
    fitter = LandmarkDetector(PATTERN).fitter
    assert fitter.fit(grey, 120, 80, 180, 140) is GROW  # the region lies inside the board
    assert fitter.fit(grey[:, 120:], 0, 0, 80, 240) is None  # ... cut by the frame's edge
    fit = fitter.fit(grey, 80, 40, 220, 180)
    assert isinstance(fit, BoardFit) and fit.landmark_id == 7
    truth = project(hom, fit.plane_points)
    assert np.linalg.norm(fit.image_points - truth, axis=1).max() < 0.5


def test_board_cut_by_the_frame_is_not_detected(detector):
    canvas = noisy_wall((240, 320), seed=10)
    paste(canvas, 7, [[-40, 60], [60, 60], [60, 160], [-40, 160]])
    assert detector.detect(finish(canvas, seed=11)) == []


def test_correlate_is_the_correlation_coefficient_except_on_flat_windows():
    rng = np.random.default_rng(2)
    image = cv2.GaussianBlur(rng.integers(0, 256, (60, 90), dtype=np.uint8), (5, 5), 1.0)
    image[:, :30] = 120 + (rng.uniform(size=(60, 30)) < 0.2)  # flat to the eye: std 0.4
    template = CorrelationTemplate(landmark_image(5, PATTERN, 20.0))
    got = correlate(image, template)
    expected = cv2.matchTemplate(image, template.image, cv2.TM_CCOEFF_NORMED)
    h, w = template.shape
    windows = np.lib.stride_tricks.sliding_window_view(image.astype(np.float64), (h, w))
    std = windows.std(axis=(2, 3))
    assert got.shape == expected.shape == std.shape
    textured = std >= MIN_WINDOW_STD
    assert textured.any() and (~textured).any()
    np.testing.assert_allclose(got[textured], expected[textured], atol=1e-3)
    # Flat windows are scaled down by their contrast instead of scoring anywhere in [-1, 1].
    assert np.all(np.abs(got[~textured]) <= std[~textured] / MIN_WINDOW_STD + 1e-3)
    with pytest.raises(ValueError, match="flat"):
        CorrelationTemplate(np.full((5, 5), 7, np.uint8))
    with pytest.raises(ValueError, match="uint8"):
        CorrelationTemplate(np.zeros((5, 5), np.float32))
