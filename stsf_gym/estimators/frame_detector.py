"""A camera frame's landmark detections, whatever the camera mode, free of lens distortion.

With a rendered camera the detector runs on ``obs["image"]``; in the fast sensor mode the env
has already simulated its output (``obs["landmark_ids"]``, ``obs["landmark_points"]``, see
:mod:`stsf_gym.envs.sensors.fast_camera`), which is unpacked into the same :class:`Detection`
records, so every estimator runs one code path in both modes.

With ``predictions`` (:class:`~stsf_gym.vision.predicted.BoardPrediction`, from an estimator's
landmark tracks), a predicted board the detector did not find is searched where and at the size
predicted (track-aided matching, :class:`~stsf_gym.vision.predicted.PredictedMatcher`). In the
fast mode the env lists the boards such a search would find (``obs["aided_ids"]``, drawn with
the matcher's fitted rate by size, :mod:`stsf_gym.envs.sensors.fast_camera`); a prediction takes
one when it is of that id, at least the matcher's smallest board size, and its centre lies
within its search radius of the board's (as the matcher's search window). ``predictions`` may be
a function that makes them: it is called only when they are needed (a fast frame without such
boards needs none) or asked for (:attr:`FrameDetector.predictions`).

With predictions the rendered frame is searched where the tracks predict first: the detector's
geometry stage runs on each predicted board's window (:meth:`LandmarkDetector.detect_at`), and
the whole frame (template search, eq. 6-7, then geometry) only when no prediction is in view or
every :data:`FULL_FRAME_EVERY` frames, so a board no track follows is found at most that many
frames late. Either way the image points are then
undistorted with the calibration the robot believes it has
(:attr:`~stsf_gym.estimators.base.SensorModel.camera_calibration`): the estimators work with
an ideal pinhole camera of that calibration's K.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from functools import lru_cache

import cv2
import numpy as np

from stsf_gym.camera_model import CameraCalibration
from stsf_gym.geometry import compiled
from stsf_gym.vision.detector import Detection, LandmarkDetector, to_grey
from stsf_gym.vision.landmarks import LandmarkPattern, square_centres
from stsf_gym.vision.predicted import BoardPrediction, PredictedMatcher

#: While tracks predict boards, the whole frame is searched every this many frames (the others:
#: the predicted windows only).
FULL_FRAME_EVERY = 3

DBL_EPSILON = float(np.finfo(np.float64).eps)


class FrameDetector:
    """``detector(obs, predictions) -> list[Detection]`` for boards whose id is in
    ``valid_ids``, their points undistorted with ``calibration`` (none: taken as they are);
    ``matcher`` searches the predicted boards the detector missed (none: no such search)."""

    def __init__(
        self,
        pattern: LandmarkPattern,
        valid_ids: set[int],
        calibration: CameraCalibration | None = None,
        matcher: PredictedMatcher | None = None,
    ) -> None:
        self.pattern, self.valid_ids = pattern, frozenset(valid_ids)
        self.calibration, self.matcher = calibration, matcher
        #: Detections of the last call that only the predicted search found.
        self.aided: list[Detection] = []
        #: The last call's detections in the image's own (distorted) pixels, and the boards it
        #: was told to expect (for recordings: :mod:`stsf_gym.recording`).
        self.found: list[Detection] = []
        self._predict: Callable[[], Sequence[BoardPrediction]] = list
        self._predictions: list[BoardPrediction] | None = None
        self._since_full_frame = FULL_FRAME_EVERY  # frames since the whole frame was searched

    def __call__(
        self,
        obs: dict,
        predictions: Sequence[BoardPrediction] | Callable[[], Sequence[BoardPrediction]] = (),
    ) -> list[Detection]:
        self.aided, self._predictions = [], None
        self._predict = predictions if callable(predictions) else lambda: predictions
        if "landmark_ids" in obs:
            found = self._unpack(obs["landmark_ids"], obs["landmark_points"])
            aided_slots = "aided_ids" in obs and bool((obs["aided_ids"] >= 0).any())
            if self.matcher is not None and aided_slots and self.predictions:
                self.aided = self._simulated_search(obs, self.predictions, found)
                found = found + self.aided
        else:
            found = self._detect(obs["image"], self.predictions)
            if self.matcher is not None and self.predictions:
                self.aided = self._search(obs["image"], self.predictions, found)
                found = found + self.aided
        self.found = found
        if self.calibration is None or not self.calibration.distorted:
            return found
        return [self._undistorted(d) for d in found]

    @property
    def predictions(self) -> list[BoardPrediction]:
        """The boards the last call was told to expect (made when first needed or asked for)."""
        if self._predictions is None:
            self._predictions = list(self._predict())
        return self._predictions

    def _detect(self, image: np.ndarray, predictions: list[BoardPrediction]) -> list[Detection]:
        """The detector's boards: in the predicted windows, or in the whole frame when none is
        predicted or its turn has come (see the module docstring)."""
        detector = _image_detector(self.pattern, self.valid_ids)
        windows = [
            p
            for p in predictions
            if p.landmark_id in self.valid_ids
            and p.size_px >= detector.min_board_px  # as small as the whole-frame search finds
            and np.isfinite(p.corners).all()
        ]
        self._since_full_frame += 1
        if not windows or self._since_full_frame >= FULL_FRAME_EVERY:
            self._since_full_frame = 0
            return _detect(self.pattern, self.valid_ids, image)
        grey = to_grey(image)
        found: dict[int, Detection] = {}
        for prediction in windows:
            if prediction.landmark_id in found:
                continue
            cx, cy = prediction.corners.mean(axis=0)
            detection = detector.detect_at(grey, cx, cy, prediction.size_px)
            if detection is not None and detection.landmark_id not in found:
                found[detection.landmark_id] = detection
        return list(found.values())

    def _search(
        self, image: np.ndarray, predictions: list[BoardPrediction], found: list[Detection]
    ) -> list[Detection]:
        """The predicted boards of ids the detector did not find, where the matcher finds them."""
        grey = to_grey(image)
        have = {d.landmark_id for d in found}
        matches = []
        for prediction in predictions:
            if prediction.landmark_id in have or prediction.landmark_id not in self.valid_ids:
                continue
            match = self.matcher.match(grey, prediction)
            if match is not None:
                matches.append(match)
                have.add(match.landmark_id)
        return matches

    def _simulated_search(
        self, obs: dict, predictions: list[BoardPrediction], found: list[Detection]
    ) -> list[Detection]:
        """The fast mode's track-aided matches: findable boards a prediction covers."""
        have = {d.landmark_id for d in found}
        candidates = [
            p
            for p in predictions
            if p.landmark_id not in have and p.size_px >= self.matcher.min_board_px
        ]
        # only the boards some candidate could take are unpacked
        wanted = self.valid_ids & {p.landmark_id for p in candidates}
        aided = self._unpack(obs["aided_ids"], obs["aided_points"], wanted)
        findable = {d.landmark_id: d for d in aided}
        matches = []
        for prediction in candidates:
            board = findable.get(prediction.landmark_id)
            if board is None or board.landmark_id in have:
                continue
            # the board's centre: its homography maps the pattern's origin there
            homography, _ = cv2.findHomography(board.plane_points, board.image_points)
            centre = homography @ np.array([0.0, 0.0, 1.0])
            offset = centre[:2] / centre[2] - prediction.corners.mean(axis=0)
            if np.hypot(*offset) <= prediction.search_px:
                matches.append(board)
                have.add(board.landmark_id)
        return matches

    def _undistorted(self, detection: Detection) -> Detection:
        """The detection with its points undistorted; the estimators use the points, so no
        homography is fitted to them (:meth:`Detection.project` fits one if asked)."""
        points = self.calibration.undistort_pixels(detection.image_points)
        return replace(detection, image_points=points, homography=None)

    def _unpack(
        self, ids: np.ndarray, points: np.ndarray, wanted: frozenset[int] | None = None
    ) -> list[Detection]:
        """The slots' boards of an id in ``wanted`` (default: the map's) whose points a
        homography fits (a degenerate board is no detection); none is fitted here
        (:meth:`Detection.project` fits one if asked)."""
        wanted = self.valid_ids if wanted is None else wanted
        detections = []
        for landmark_id, slot in zip(ids.tolist(), points.reshape(len(ids), -1, 2), strict=True):
            if landmark_id not in wanted:
                continue
            plane = square_centres(landmark_id, self.pattern)
            image = slot[: len(plane)].astype(np.float64)
            if not _homography_fits(plane, image):
                continue
            detections.append(
                Detection(
                    landmark_id=landmark_id,
                    image_points=image,
                    plane_points=plane,
                    indices=np.arange(len(plane)),
                    score=1.0,
                    homography=None,
                )
            )
        return detections


def _homography_fits(plane: np.ndarray, image: np.ndarray) -> bool:
    """Whether ``cv2.findHomography(plane, image)`` (least squares, every point) fits one,
    without fitting it: OpenCV takes the points as float32 and gives up when the summed
    absolute deviation from the mean, of x or of y in either set, is below ``DBL_EPSILON``
    (its normalisation would divide by it). The sums are sequential in double, as OpenCV's
    loops; ``tests/estimators/test_fast_aided.py`` checks the answer against OpenCV's."""
    return _spread_in_every_axis(np.hstack([plane, image]).astype(np.float32).astype(np.float64))


@compiled
def _spread_in_every_axis(points: np.ndarray) -> bool:
    """Whether every column of ``points`` (N, 4) sums, sequentially in double, an absolute
    deviation from its mean of at least ``DBL_EPSILON`` (a NaN deviation, from inf - inf,
    passes, as in OpenCV)."""
    count = points.shape[0]
    for column in range(points.shape[1]):
        total = 0.0
        for row in range(count):
            total += points[row, column]
        mean = total / count
        deviation = 0.0
        for row in range(count):
            deviation += abs(points[row, column] - mean)
        if deviation < DBL_EPSILON:
            return False
    return True


#: The last image detected and what was found in it: an evaluation's floor recorder detects the
#: frame the estimator just did (same image object, same map), and gets its detections.
_last: list = [None, None, None, []]


def _detect(pattern: LandmarkPattern, valid_ids: frozenset[int], image: np.ndarray):
    if _last[0] is not image or _last[1] != pattern or _last[2] != valid_ids:
        _last[:] = [image, pattern, valid_ids, _image_detector(pattern, valid_ids).detect(image)]
    return list(_last[3])


@lru_cache(maxsize=8)
def _image_detector(pattern: LandmarkPattern, valid_ids: frozenset[int]) -> LandmarkDetector:
    """One detector (its templates are costly to build) per pattern and map, per process."""
    return LandmarkDetector(pattern, valid_ids=set(valid_ids))
