"""An episode as a Rerun recording (``.rrd``), on a ``sim_time`` timeline; no viewer needed.

Entity paths (open the file with ``rerun FILE.rrd``):

- ``world/walls``, ``world/landmarks`` (boards labelled with their ids), ``world/path``: the map
  in 3-D, static;
- ``world/truth`` and ``world/estimate/<name>``: the pose at each step, the estimate with its
  2-sigma position ellipse (``.../ellipse``); ``world/trajectory/*``: whole trajectories, at
  the end;
- ``world/sonar``: each transducer's cone cut at its range;
- ``camera/image`` (JPEG), ``camera/detections`` (each detected board's squares, labelled with
  its id), ``camera/aided`` (boards only the track-aided search found), ``camera/predictions``
  (the boards the tracks predicted): from the estimator's detector; in the fast sensor mode the
  simulated detections are drawn instead of an image;
- ``metrics/position_error/<name>``, ``metrics/nees/<name>``, ``metrics/frames_matched/<name>``
  and ``agent/action/{v,w}``: scalars per step.
"""

from __future__ import annotations

import math
from collections import defaultdict
from pathlib import Path

import cv2
import numpy as np
import rerun as rr

from stsf_gym.metrics import nees, pose_error
from stsf_gym.recording.records import EpisodeStart, StepRecord

TIMELINE = "sim_time"
JPEG_QUALITY = 85
ELLIPSE_POINTS, ELLIPSE_SIGMA = 32, 2.0
ROBOT_Z = 0.05  # height the poses are drawn at (m)


class RerunRecorder:
    """Writes one episode to the ``.rrd`` file ``path``."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.rec = rr.RecordingStream("stsf-gym", recording_id=self.path.stem)
        self.rec.save(str(self.path))
        self.steps: dict[str, list] = defaultdict(list)
        self.frames: dict[str, list] = defaultdict(list)

    def start(self, start: EpisodeStart) -> None:
        """Log the static world: walls, boards with their ids and the path."""
        self.layout, model = start.layout, start.model
        walls = np.asarray(model.walls, float).reshape(-1, 4)
        length = np.hypot(walls[:, 2] - walls[:, 0], walls[:, 3] - walls[:, 1])
        height = start.layout.wall_height
        self.rec.log(
            "world/walls",
            rr.Boxes3D(
                centers=np.column_stack(
                    [(walls[:, :2] + walls[:, 2:]) / 2, np.full(len(walls), height / 2)]
                ),
                half_sizes=np.column_stack(
                    [length / 2, np.full(len(walls), 0.05), np.full(len(walls), height / 2)]
                ),
                rotation_axis_angles=[
                    rr.RotationAxisAngle(axis=[0, 0, 1], radians=math.atan2(y2 - y1, x2 - x1))
                    for x1, y1, x2, y2 in walls
                ],
                colors=[180, 180, 190],
            ),
            static=True,
        )
        boards = list(model.landmarks.values())
        half = model.pattern.size / 2
        self.rec.log(
            "world/landmarks",
            rr.Boxes3D(
                centers=[b.centre for b in boards],
                half_sizes=[[0.01, half, half]] * len(boards),
                rotation_axis_angles=[
                    rr.RotationAxisAngle(
                        axis=[0, 0, 1], radians=math.atan2(b.normal[1], b.normal[0])
                    )
                    for b in boards
                ],
                labels=[f"{b.id}" for b in boards],
                colors=[20, 20, 20],
            ),
            static=True,
        )
        if "path" in start.meta:
            path = np.asarray(start.meta["path"], float)
            strip = np.column_stack([path, np.zeros(len(path))])
            self.rec.log("world/path", rr.LineStrips3D([strip], colors=[90, 160, 90]), static=True)

    def step(self, record: StepRecord) -> None:
        """Buffer the step; everything is sent by entity, as columns, at :meth:`close`."""
        steps = self.steps
        steps["time"].append(record.time)
        steps["truth"].append(np.asarray(record.true_pose, float))
        steps["sonar"].append(np.asarray(record.obs["sonar"], float))
        for name, (mean, cov) in record.estimates.items():
            steps.setdefault(f"estimate/{name}", []).append((mean, cov))
            steps.setdefault(f"matched/{name}", []).append(record.counters.get("frames_matched", 0))
        if record.action is not None:
            steps["action_time"].append(record.time)
            steps["action"].append(np.clip(np.asarray(record.action, float).ravel()[:2], -1, 1))
        if record.obs["image_new"]:
            self._frame(record)

    def _frame(self, record: StepRecord) -> None:
        obs, frames = record.obs, self.frames
        frames["time"].append(record.time)
        if "image" in obs:
            bgr = cv2.cvtColor(obs["image"], cv2.COLOR_RGB2BGR)
            ok, jpeg = cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
            frames["image"].append(jpeg.tobytes() if ok else b"")
        if record.detections is None and "landmark_ids" in obs:  # the fast mode's detections
            ids = np.asarray(obs["landmark_ids"])
            slots = np.asarray(obs["landmark_points"]).reshape(len(ids), -1, 2)
            found = [(i, s[np.isfinite(s).all(axis=1)]) for i, s in zip(ids, slots, strict=True)]
            found = [(i, s) for i, s in found if i >= 0]
            aided, predictions = [], []
        else:
            detections = record.detections
            found = (
                [(d.landmark_id, d.image_points) for d in detections.found] if detections else []
            )
            aided = (
                [(d.landmark_id, d.image_points) for d in detections.aided] if detections else []
            )
            predictions = detections.predictions if detections else []
        frames["detections"].append(found)
        frames["aided"].append(aided)
        frames["predictions"].append(
            [(p.landmark_id, np.vstack([p.corners, p.corners[:1]])) for p in predictions]
        )

    def close(self, end: dict | None = None) -> None:
        """Send the buffered steps and frames and close the recording."""
        if self.steps["time"]:
            self._send_steps()
        if self.frames["time"]:
            self._send_frames()
        self.rec.flush()
        self.rec.disconnect()

    def _send(self, entity: str, times, columns) -> None:
        self.rec.send_columns(
            entity, indexes=[rr.TimeColumn(TIMELINE, duration=times)], columns=columns
        )

    def _send_steps(self) -> None:
        steps, layout = self.steps, self.layout
        times, truth = np.array(steps["time"]), np.array(steps["truth"])
        self._poses("truth", times, truth, [40, 200, 40])
        for key in [k for k in steps if k.startswith("estimate/")]:
            name = key.split("/", 1)[1]
            means = np.array([m for m, _ in steps[key]])
            covs = np.array([c for _, c in steps[key]])
            self._poses(f"estimate/{name}", times, means, [220, 60, 60])
            ellipses = _ellipses(means, covs)
            self._send(
                f"world/estimate/{name}/ellipse", times, rr.LineStrips3D.columns(strips=ellipses)
            )
            error = pose_error(means, truth)
            scalars = {
                "position_error": np.hypot(error[:, 0], error[:, 1]),
                "nees": nees(error, covs),
                "frames_matched": np.array(steps[f"matched/{name}"], float),
            }
            for metric, values in scalars.items():
                self._send(f"metrics/{metric}/{name}", times, rr.Scalars.columns(scalars=values))
        if steps["action"]:
            action_times, action = np.array(steps["action_time"]), np.array(steps["action"])
            self._send(
                "agent/action/v",
                action_times,
                rr.Scalars.columns(scalars=action[:, 0] * layout.max_speed),
            )
            self._send(
                "agent/action/w",
                action_times,
                rr.Scalars.columns(scalars=action[:, 1] * layout.max_yaw_rate),
            )
        cones = _sonar_cones(truth, np.array(steps["sonar"]), layout)
        self.rec.log(
            "world/sonar", rr.LineStrips3D.from_fields(colors=[[80, 140, 230]]), static=True
        )
        self._send(
            "world/sonar",
            times,
            rr.LineStrips3D.columns(strips=cones.reshape(-1, 4, 3)).partition(
                [cones.shape[1]] * len(times)
            ),
        )

    def _poses(self, name: str, times, poses: np.ndarray, color) -> None:
        """The pose at each step as an arrow, and the whole trajectory (static)."""
        origins = np.column_stack([poses[:, :2], np.full(len(poses), ROBOT_Z)])
        heading = 0.3 * np.column_stack(
            [np.cos(poses[:, 2]), np.sin(poses[:, 2]), np.zeros(len(poses))]
        )
        self.rec.log(f"world/{name}", rr.Arrows3D.from_fields(colors=[color]), static=True)
        self._send(f"world/{name}", times, rr.Arrows3D.columns(origins=origins, vectors=heading))
        label = name.split("/")[-1]
        self.rec.log(
            f"world/trajectory/{label}", rr.LineStrips3D([origins], colors=[color]), static=True
        )

    def _send_frames(self) -> None:
        frames = self.frames
        times = np.array(frames["time"])
        if frames["image"]:
            blobs = frames["image"]
            self._send(
                "camera/image",
                times,
                rr.EncodedImage.columns(blob=blobs, media_type=["image/jpeg"] * len(blobs)),
            )
        for entity, color in (("detections", [60, 220, 60]), ("aided", [240, 160, 40])):
            boards = frames[entity]
            points = [p for frame in boards for _, p in frame]
            counts = [sum(len(p) for _, p in frame) for frame in boards]
            self.rec.log(
                f"camera/{entity}", rr.Points2D.from_fields(colors=[color], radii=2.0), static=True
            )
            positions = np.vstack(points) if points else np.zeros((0, 2))
            self._send(
                f"camera/{entity}",
                times,
                rr.Points2D.columns(positions=positions).partition(counts),
            )
            centres = [p.mean(axis=0) for frame in boards for _, p in frame]
            labels = [str(int(i)) for frame in boards for i, _ in frame]
            self._send(
                f"camera/{entity}/ids",
                times,
                rr.Points2D.columns(
                    positions=np.array(centres).reshape(-1, 2), labels=labels
                ).partition([len(f) for f in boards]),
            )
        predicted = frames["predictions"]
        strips = [s for frame in predicted for _, s in frame]
        labels = [f"{i}?" for frame in predicted for i, _ in frame]
        self.rec.log(
            "camera/predictions", rr.LineStrips2D.from_fields(colors=[[240, 240, 60]]), static=True
        )
        self._send(
            "camera/predictions",
            times,
            rr.LineStrips2D.columns(strips=strips, labels=labels).partition(
                [len(f) for f in predicted]
            ),
        )


def _sonar_cones(poses: np.ndarray, ranges: np.ndarray, layout) -> np.ndarray:
    """Each transducer's beam as a closed triangle (apex, two edges at the range): (N, K, 4, 3)."""
    heading = poses[:, 2:3] + layout.sonar_axes[None, :]  # (N, K)
    apex = poses[:, None, :2] + layout.body_radius * np.stack(
        [np.cos(heading), np.sin(heading)], -1
    )
    half = layout.sonar_fov / 2
    edges = [
        apex
        + ranges[..., None] * np.stack([np.cos(heading + s * half), np.sin(heading + s * half)], -1)
        for s in (-1, 1)
    ]
    ring = np.stack([apex, edges[0], edges[1], apex], axis=2)  # (N, K, 4, 2)
    return np.concatenate([ring, np.full((*ring.shape[:3], 1), layout.sonar_height)], axis=-1)


def _ellipses(means: np.ndarray, covs: np.ndarray) -> np.ndarray:
    """The ``ELLIPSE_SIGMA`` ellipse of each position covariance around its mean: (N, M, 3)."""
    values, vectors = np.linalg.eigh(covs[:, :2, :2])
    angles = np.linspace(0, 2 * np.pi, ELLIPSE_POINTS)
    circle = np.stack([np.cos(angles), np.sin(angles)])  # (2, M)
    radii = ELLIPSE_SIGMA * np.sqrt(np.maximum(values, 0))[:, :, None]  # (N, 2, 1)
    xy = np.swapaxes(vectors @ (radii * circle), 1, 2) + means[:, None, :2]
    return np.concatenate([xy, np.full((*xy.shape[:2], 1), ROBOT_Z)], axis=-1)
