"""The fast mode keeps STSF's track-aided matching: boards the detector missed that a
predicted search would find are simulated, and taken only where a prediction covers them."""

from __future__ import annotations

import numpy as np

from stsf_gym.envs.config import load_config
from stsf_gym.envs.sensors.fast_camera import aided_probability, detection_probability
from stsf_gym.estimators.frame_detector import FrameDetector
from stsf_gym.vision.landmarks import board_corners, square_centres
from stsf_gym.vision.predicted import BoardPrediction, PredictedMatcher

PATTERN = load_config().world.landmark_pattern


def findable_obs(landmark_id: int, centre: np.ndarray, scale: float) -> tuple[dict, np.ndarray]:
    """A fast-mode frame that detected nothing but lists one findable board (fronto-parallel,
    ``scale`` px per m, centred at ``centre``); and that board's corners in pixels."""
    squares = centre + square_centres(landmark_id, PATTERN) * [scale, -scale]
    values = 2 * PATTERN.grid**2
    points = np.zeros(4 * values, np.float32)
    points[: squares.size] = squares.ravel()
    obs = {
        "landmark_ids": np.full(4, -1),
        "landmark_points": np.zeros(4 * values, np.float32),
        "aided_ids": np.array([landmark_id, -1, -1, -1]),
        "aided_points": points,
    }
    return obs, centre + board_corners(PATTERN) * [scale, -scale]


def test_a_prediction_within_its_search_radius_finds_the_board():
    detector = FrameDetector(PATTERN, {5, 6}, matcher=PredictedMatcher(PATTERN))
    obs, corners = findable_obs(5, np.array([160.0, 120.0]), 40.0)  # a 24 px board
    near = BoardPrediction(5, corners + np.array([3.0, -2.0]), 6.0)
    found = detector(obs, [near])
    assert [d.landmark_id for d in found] == [5] and detector.aided == found
    assert (
        detector(obs, [BoardPrediction(5, corners + np.array([8.0, 0.0]), 6.0)]) == []
    )  # too far off
    assert detector(obs, [BoardPrediction(6, corners, 6.0)]) == []  # another id
    assert detector(obs, []) == []  # nothing predicted: the detector's output only
    plain = FrameDetector(PATTERN, {5, 6})  # conventional fusion: no predicted search
    assert plain(obs, [near]) == []


def test_predictions_are_made_only_when_a_fast_frame_needs_them_or_they_are_asked_for():
    """A fast frame without findable boards needs no prediction: the estimator's function that
    makes them is not called, unless a reader (a recording) asks for them; then once."""
    detector = FrameDetector(PATTERN, {5, 6}, matcher=PredictedMatcher(PATTERN))
    obs, corners = findable_obs(5, np.array([160.0, 120.0]), 40.0)
    near = BoardPrediction(5, corners + np.array([3.0, -2.0]), 6.0)
    calls = []

    def predict():
        calls.append(1)
        return [near]

    assert [d.landmark_id for d in detector(obs, predict)] == [5] and len(calls) == 1
    nothing_findable = {**obs, "aided_ids": np.full(4, -1)}
    assert detector(nothing_findable, predict) == [] and len(calls) == 1
    assert detector.predictions == [near] and detector.predictions == [near]
    assert len(calls) == 2


def test_the_search_finds_smaller_boards_than_the_detector():
    cfg = load_config().camera.fast  # the paper profile's fitted numbers
    sizes = np.array([12.0, 14.0, 18.0, 22.0])
    assert np.all(aided_probability(sizes, cfg) > detection_probability(sizes, cfg))
    assert cfg.aided_size_px < cfg.detect_size_px


def test_fast_frames_list_findable_boards_only_when_the_detector_missed_them():
    import gymnasium as gym

    import stsf_gym  # noqa: F401

    env = gym.make("stsf_gym/Corridor-v0", camera__mode="fast", camera__control="pan")
    obs, _ = env.reset(seed=0)
    seen_aided = 0
    for _ in range(300):
        obs, *_ = env.step(np.array([0.5, 0.0, 0.0]))
        if obs["image_new"]:
            plain = set(obs["landmark_ids"].tolist()) - {-1}
            aided = set(obs["aided_ids"].tolist()) - {-1}
            assert not plain & aided
            assert aided <= set(env.unwrapped.landmarks_in_view())
            seen_aided += bool(aided)
    env.close()
    assert seen_aided > 0


def test_fast_detections_fit_their_homography_only_when_asked():
    """The fast mode's detections carry no homography (the estimators use the points, raw
    or undistorted); ``project`` fits one on demand, to the points the detection holds."""
    import cv2

    from stsf_gym.camera_model import CameraCalibration

    K = np.array([[300.0, 0.0, 159.5], [0.0, 300.0, 119.5], [0.0, 0.0, 1.0]])
    lens = CameraCalibration(K, np.array([-0.2, 0.05, 0.001, -0.001, 0.0]))
    obs, _ = findable_obs(5, np.array([150.0, 110.0]), 40.0)
    obs["landmark_ids"], obs["landmark_points"] = obs["aided_ids"], obs["aided_points"]
    (raw,) = FrameDetector(PATTERN, {5})(obs)
    (detection,) = FrameDetector(PATTERN, {5}, lens)(obs)
    assert raw.homography is None and detection.homography is None
    np.testing.assert_array_equal(detection.image_points, lens.undistort_pixels(raw.image_points))
    fitted, _ = cv2.findHomography(detection.plane_points, detection.image_points)
    origin = np.zeros((1, 2))
    expected = fitted @ np.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(detection.project(origin)[0], expected[:2] / expected[2])
    assert not np.allclose(detection.project(origin), raw.project(origin))  # the lens moved it


def test_degenerate_boards_are_those_opencv_fits_no_homography():
    """A fast-mode board is dropped exactly when OpenCV's least-squares fit would fail:
    checked against ``cv2.findHomography`` on random boards and on boards whose x or y
    spread is nil, one float32 step or below ``DBL_EPSILON``."""
    import cv2

    from stsf_gym.estimators.frame_detector import _homography_fits

    rng = np.random.default_rng(0)
    failures = 0
    for trial in range(3000):
        k = int(rng.integers(4, 20))
        plane, image = rng.normal(size=(k, 2)) * 0.1, rng.uniform(0.0, 320.0, size=(k, 2))
        column = int(rng.integers(2))
        match trial % 5:
            case 1:
                image[:, column] = image[0, column]
            case 2:
                image[:, column] = image[0, column]
                image[rng.integers(k), column] = np.nextafter(np.float32(image[0, column]), 1e9)
            case 3:
                plane[:, column] = plane[0, column]
            case 4:
                image[:, column] = 1e-17 * rng.normal(size=k)
        fitted, _ = cv2.findHomography(plane, image)
        assert _homography_fits(plane, image) == (fitted is not None), (trial, k)
        failures += fitted is None
    assert 1000 < failures < 3000  # both answers were exercised
