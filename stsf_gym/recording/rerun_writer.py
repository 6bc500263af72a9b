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
        self.trajectories: dict[str, list] = {}

    def start(self, start: EpisodeStart) -> None:
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
        self.rec.set_time(TIMELINE, duration=record.time)
        truth = record.true_pose
        self._pose("world/truth", truth, [40, 200, 40])
        self.trajectories.setdefault("truth", []).append(truth)
        for name, (mean, cov) in record.estimates.items():
            self._pose(f"world/estimate/{name}", mean, [220, 60, 60])
            self.rec.log(f"world/estimate/{name}/ellipse", rr.LineStrips3D([_ellipse(mean, cov)]))
            self.trajectories.setdefault(name, []).append(mean)
            error = pose_error(mean, truth)
            self.rec.log(f"metrics/position_error/{name}", rr.Scalars(float(np.hypot(*error[:2]))))
            self.rec.log(f"metrics/nees/{name}", rr.Scalars(float(nees(error[None], cov[None])[0])))
            matched = record.counters.get("frames_matched", 0)
            self.rec.log(f"metrics/frames_matched/{name}", rr.Scalars(float(matched)))
        if record.action is not None:
            v, w = np.clip(np.asarray(record.action, float).ravel()[:2], -1, 1)
            self.rec.log("agent/action/v", rr.Scalars(v * self.layout.max_speed))
            self.rec.log("agent/action/w", rr.Scalars(w * self.layout.max_yaw_rate))
        self._sonar(truth, record.obs["sonar"])
        if record.obs["image_new"]:
            self._camera(record)

    def _pose(self, entity: str, pose, color) -> None:
        x, y, yaw = pose
        self.rec.log(
            entity,
            rr.Arrows3D(
                origins=[[x, y, ROBOT_Z]],
                vectors=[[0.3 * math.cos(yaw), 0.3 * math.sin(yaw), 0.0]],
                colors=[color],
            ),
        )

    def _sonar(self, pose, ranges) -> None:
        layout, (x, y, yaw) = self.layout, pose
        cones = []
        for axis, r in zip(layout.sonar_axes, ranges, strict=True):
            heading = yaw + axis
            apex = np.array([x, y]) + layout.body_radius * np.array(
                [np.cos(heading), np.sin(heading)]
            )
            edges = [heading - layout.sonar_fov / 2, heading + layout.sonar_fov / 2]
            ends = [apex + r * np.array([np.cos(a), np.sin(a)]) for a in edges]
            ring = np.array([apex, ends[0], ends[1], apex])
            cones.append(np.column_stack([ring, np.full(4, layout.sonar_height)]))
        self.rec.log("world/sonar", rr.LineStrips3D(cones, colors=[80, 140, 230]))

    def _camera(self, record: StepRecord) -> None:
        obs = record.obs
        if "image" in obs:
            ok, jpeg = cv2.imencode(
                ".jpg",
                cv2.cvtColor(obs["image"], cv2.COLOR_RGB2BGR),
                [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY],
            )
            if ok:
                self.rec.log(
                    "camera/image",
                    rr.EncodedImage(contents=jpeg.tobytes(), media_type="image/jpeg"),
                )
        found = record.detections.found if record.detections else None
        if found is None and "landmark_ids" in obs:  # the fast mode's detections, drawn
            ids = np.asarray(obs["landmark_ids"])
            slots = np.asarray(obs["landmark_points"]).reshape(len(ids), -1, 2)
            found = [
                (i, s[np.isfinite(s).all(axis=1)])
                for i, s in zip(ids, slots, strict=True)
                if i >= 0
            ]
        else:
            found = [(d.landmark_id, d.image_points) for d in found or []]
        self._boards("camera/detections", found, [60, 220, 60])
        if record.detections is not None:
            aided = [(d.landmark_id, d.image_points) for d in record.detections.aided]
            self._boards("camera/aided", aided, [240, 160, 40])
            self.rec.log(
                "camera/predictions",
                rr.LineStrips2D(
                    [np.vstack([p.corners, p.corners[:1]]) for p in record.detections.predictions],
                    labels=[f"{p.landmark_id}?" for p in record.detections.predictions],
                    colors=[240, 240, 60],
                ),
            )

    def _boards(self, entity: str, boards: list, color) -> None:
        points = [np.asarray(p, float) for _, p in boards]
        self.rec.log(
            entity,
            rr.Points2D(
                np.vstack(points) if points else np.zeros((0, 2)),
                colors=[color],
                radii=2.0,
            ),
        )
        self.rec.log(
            f"{entity}/ids",
            rr.Points2D(
                [p.mean(axis=0) for p in points] if points else np.zeros((0, 2)),
                labels=[str(int(i)) for i, _ in boards],
                colors=[color],
                radii=0.5,
            ),
        )

    def close(self, end: dict | None = None) -> None:
        for name, poses in self.trajectories.items():
            xy = np.asarray(poses)[:, :2]
            strip = np.column_stack([xy, np.full(len(xy), ROBOT_Z)])
            color = [40, 200, 40] if name == "truth" else [220, 60, 60]
            self.rec.log(
                f"world/trajectory/{name}", rr.LineStrips3D([strip], colors=[color]), static=True
            )
        self.trajectories = {}
        self.rec.flush()
        self.rec.disconnect()


def _ellipse(mean, cov) -> np.ndarray:
    """The ``ELLIPSE_SIGMA`` ellipse of the position covariance around ``mean`` (3-D points)."""
    values, vectors = np.linalg.eigh(np.asarray(cov)[:2, :2])
    angles = np.linspace(0, 2 * np.pi, ELLIPSE_POINTS)
    circle = np.stack([np.cos(angles), np.sin(angles)])
    xy = (vectors @ (ELLIPSE_SIGMA * np.sqrt(np.maximum(values, 0))[:, None] * circle)).T + mean[:2]
    return np.column_stack([xy, np.full(len(xy), ROBOT_Z)])
