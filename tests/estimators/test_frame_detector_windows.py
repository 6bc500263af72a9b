"""A frame's detection searches the windows the tracks predict, the whole frame in its turn."""

import cv2
import numpy as np

from stsf_gym.estimators import frame_detector
from stsf_gym.estimators.frame_detector import FULL_FRAME_EVERY, FrameDetector
from stsf_gym.vision.landmarks import LandmarkPattern, landmark_image
from stsf_gym.vision.predicted import BoardPrediction

PATTERN = LandmarkPattern()
LANDMARK = 5
#: the board's corners in the image, in board_corners order (top-left, top-right, bottom-right,
#: bottom-left)
CORNERS = np.array([[130.0, 70.0], [194.0, 72.0], [192.0, 136.0], [128.0, 134.0]])


def board_frame() -> np.ndarray:
    """An RGB frame of one board (corners :data:`CORNERS`) on a grey wall with noise."""
    texture = landmark_image(LANDMARK, PATTERN).astype(np.float32)
    n = texture.shape[0]
    source = np.float32([[-0.5, -0.5], [n - 0.5, -0.5], [n - 0.5, n - 0.5], [-0.5, n - 0.5]])
    warp = cv2.getPerspectiveTransform(source, np.float32(CORNERS))
    board = cv2.warpPerspective(texture, warp, (320, 240), flags=cv2.INTER_AREA)
    cover = cv2.warpPerspective(np.ones_like(texture), warp, (320, 240), flags=cv2.INTER_AREA)
    grey = cover * board * 0.85 + (1 - cover) * 160.0
    grey += np.random.default_rng(0).normal(0, 2.0, grey.shape)
    return np.repeat(np.clip(grey, 0, 255).round().astype(np.uint8)[..., None], 3, axis=2)


def test_predicted_windows_replace_the_whole_frame_between_its_turns(monkeypatch):
    image = board_frame()
    whole_frame = []
    detect = frame_detector._detect
    monkeypatch.setattr(
        frame_detector, "_detect", lambda *args: whole_frame.append(1) or detect(*args)
    )
    frame_detector._last[0] = None  # no cached detections of an earlier test's image
    detector = FrameDetector(PATTERN, {LANDMARK})
    prediction = BoardPrediction(LANDMARK, CORNERS + 2.0, search_px=6.0)
    runs = [detector({"image": image}, [prediction]) for _ in range(2 * FULL_FRAME_EVERY)]
    assert len(whole_frame) == 2  # the first frame, then every FULL_FRAME_EVERY-th
    assert all(len(found) == 1 and found[0].landmark_id == LANDMARK for found in runs)
    full, windowed = runs[0][0], runs[1][0]
    assert np.isfinite(full.score) and np.isnan(windowed.score)  # windowed: no template search
    assert np.abs(windowed.image_points - full.image_points).max() < 0.05
    assert np.abs(full.corners - CORNERS).max() < 1.0  # the frame is drawn as described


def test_a_board_no_prediction_covers_waits_for_the_whole_frame():
    frame_detector._last[0] = None
    image = board_frame()
    detector = FrameDetector(PATTERN, {LANDMARK})
    elsewhere = BoardPrediction(LANDMARK, CORNERS + np.array([120.0, 90.0]), search_px=6.0)
    found = [len(detector({"image": image}, [elsewhere])) for _ in range(FULL_FRAME_EVERY + 1)]
    assert found == [1] + [0] * (FULL_FRAME_EVERY - 1) + [1]
    assert all(len(detector({"image": image})) == 1 for _ in range(3))  # none predicted
