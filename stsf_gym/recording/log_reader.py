"""A log (MCAP of :mod:`.topics`) read back as the observations an estimator was given.

Steps are the ``/wheel_ticks`` messages: the first is the start (the estimator is reset
there, not updated), each later one a control step whose encoder ticks are the difference of
the cumulative counts. A camera frame (image, or fast-mode detections) belongs to the first
step at or after its log time, its arrival (``image_new`` 1 there); its header stamp is its
exposure (``image_time``, earlier when the camera has a latency). The mount angles and sonar
ranges of a step are the latest at or before it; times are seconds from the first step. The
observation dicts match the env's (:class:`stsf_gym.envs.corridor_env.CorridorEnv`), so
estimators run on them unchanged.
Nothing here imports the simulator.
"""

from __future__ import annotations

import bisect
import json
from collections import defaultdict
from collections.abc import Iterator
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Annotated

import cv2
import numpy as np
from rosbags.rosbag2 import Reader

from stsf_gym.estimators import SensorModel
from stsf_gym.recording import ros_messages as ros
from stsf_gym.recording import topics
from stsf_gym.recording.sensor_model_json import sensor_model_from_dict
from stsf_gym.validation import ConfigError, Coordinate, NonNegative, Positive, Range, build

#: Topics a replay does not need (for looking at only), left unread.
NOT_READ = frozenset({topics.TF, topics.TF_STATIC, topics.CMD_VEL, topics.CAMERA_INFO})
#: The first bytes of a PNG file: the one compressed frame format that is lossless.
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@dataclass(frozen=True)
class CameraLatency:
    """The recorded camera's latency (``camera.latency``): a replay keeps the live run's
    history of late frames."""

    delay_s: NonNegative = 0.0
    jitter_s: NonNegative = 0.0


@dataclass(frozen=True)
class EpisodeDocument:
    """The keys of ``/robot/episode`` a replay reads, checked as a config's; others are kept
    as they are (``frames`` and ``lossless`` are claims: the frames themselves decide)."""

    control_dt: Positive  # s between two steps
    camera_latency: CameraLatency = CameraLatency()  # the live wrapper's history of late frames
    seed: Annotated[int, Range(ge=0)] | None = None
    path: tuple[tuple[Coordinate, Coordinate], ...] = ()  # for the path error


EPISODE_KEYS = frozenset(f.name for f in fields(EpisodeDocument))


@dataclass
class RecordedLog:
    """Everything a replay needs from one log, camera frames still encoded."""

    path: Path
    model: SensorModel
    episode: dict
    initial_pose: np.ndarray
    initial_cov: np.ndarray
    stamps: np.ndarray  # ns of each step
    ticks: np.ndarray  # (N, 2) int64 deltas (0 at the start)
    frames: list[tuple[int, object]]  # (log time, message) of camera frames, in time order
    pan_tilt: list[tuple[int, np.ndarray]]
    sonar: list[tuple[int, np.ndarray]]
    aided: dict[int, object]  # stamp -> the fast mode's track-aided slots of that frame
    truth: np.ndarray | None  # (N, 3) true poses at the steps, when recorded
    topics: frozenset[str] = frozenset()  # the topics that hold messages
    estimates: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    end: dict = field(default_factory=dict)  # the episode's ending ("outcome"), if recorded

    @property
    def times(self) -> np.ndarray:
        """Seconds of each step from the first."""
        return (self.stamps - self.stamps[0]) / 1e9

    @property
    def control_dt(self) -> float:
        return float(self.episode["control_dt"])

    @property
    def camera_latency(self) -> CameraLatency:
        """The latency of the recorded camera (none for a log that does not give one)."""
        return build(CameraLatency, self.episode.get("camera_latency", {}), "camera_latency")

    @property
    def lossless(self) -> bool:
        """Whether every camera frame is stored lossless: raw images, detections or PNG, as
        the compressed frames' own bytes say (whatever the episode file claims)."""
        return all(
            bytes(message.data[: len(PNG_SIGNATURE)]) == PNG_SIGNATURE
            for _, message in self.frames
            if hasattr(message, "format")  # CompressedImage
        )

    def observations(self) -> Iterator[dict]:
        """The observation of each step, the start's first."""
        frame_at = [bisect.bisect_left(self.stamps, stamp) for stamp, _ in self.frames]
        new_frames = defaultdict(list)
        for index, frame in zip(frame_at, self.frames, strict=True):
            new_frames[index].append(frame)
        camera: dict = {}
        pan_tilt_at = [stamp for stamp, _ in self.pan_tilt]
        sonar_at = [stamp for stamp, _ in self.sonar]
        exposure = np.array([-1.0])  # no frame yet, as the env gives it
        for k, stamp in enumerate(self.stamps):
            if new_frames.get(k):
                _, message = new_frames[k][-1]
                camera = decode_frame(message)
                stamp_of_frame = ros.stamp_ns(message)
                exposure = np.array([(stamp_of_frame - self.stamps[0]) / 1e9])
                if stamp_of_frame in self.aided:  # the fast mode's track-aided slots
                    ids, points = ros.slots_of(ros.detection_points(self.aided[stamp_of_frame]))
                    camera.update(aided_ids=ids, aided_points=points)
            yield {
                **camera,
                "image_new": int(bool(new_frames.get(k))),
                "camera_pan_tilt": _latest(
                    self.pan_tilt, pan_tilt_at, stamp, np.zeros(2, np.float32)
                ),
                "sonar": _latest(self.sonar, sonar_at, stamp, np.zeros(0, np.float32)),
                "encoders": self.ticks[k].copy(),
                "encoders_time": np.array([(stamp - self.stamps[0]) / 1e9]),
                "image_time": exposure.copy(),
            }


def _latest(series: list[tuple[int, np.ndarray]], stamps: list[int], stamp: int, default):
    """The value of ``series`` (stamps ``stamps``) at or before ``stamp``, else ``default``."""
    i = bisect.bisect_right(stamps, stamp) - 1
    return (series[i][1] if i >= 0 else default).copy()


def decode_frame(message) -> dict:
    """The observation entries of one camera message: ``image`` (RGB uint8) or the fast
    mode's ``landmark_ids`` and ``landmark_points``."""
    if hasattr(message, "format"):  # CompressedImage
        bgr = cv2.imdecode(np.asarray(message.data, np.uint8), cv2.IMREAD_COLOR)
        return {"image": cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)}
    if hasattr(message, "encoding"):  # Image
        if message.encoding != "rgb8":
            raise ConfigError(f"camera images must be rgb8, got {message.encoding!r}")
        data = np.asarray(message.data, np.uint8)
        return {"image": data.reshape(message.height, message.width, 3).copy()}
    ids, points = ros.slots_of(ros.detection_points(message))
    return {"landmark_ids": ids, "landmark_points": points}


def read_log(path: str | Path) -> RecordedLog:
    """Read a log; a missing required topic or an unreadable file is a :class:`ConfigError` naming
    the file."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no log file {path}")
    by_topic: dict[str, list] = defaultdict(list)
    frames = []  # (log time, message): a frame arrives at its log time
    try:
        with Reader(path) as reader:
            wanted = [c for c in reader.connections if c.topic not in NOT_READ]
            for connection, log_time, data in reader.messages(connections=wanted):
                message = ros.deserialize(data, connection.msgtype)
                by_topic[connection.topic].append(message)
                if connection.topic in topics.CAMERA:
                    frames.append((log_time, message))
    except Exception as err:
        raise ConfigError(f"{path}: not a readable MCAP log ({err})") from None
    missing = [t for t in topics.REQUIRED if not by_topic.get(t)]
    if missing:
        raise ConfigError(f"{path}: missing topic(s) {missing} (see docs/log_format.md)")
    model = sensor_model_from_dict(
        _json(by_topic, topics.SENSOR_MODEL, path), f"{path} {topics.SENSOR_MODEL}"
    )
    episode = _json(by_topic, topics.EPISODE, path)
    checked = {key: value for key, value in episode.items() if key in EPISODE_KEYS}
    try:
        build(EpisodeDocument, checked, "")
    except ConfigError as err:
        raise ConfigError(err.message, err.key, f"{path} {topics.EPISODE}") from None
    initial_pose, initial_cov = ros.planar_pose(by_topic[topics.INITIAL_POSE][0])
    wheels = sorted(by_topic[topics.WHEEL_TICKS], key=ros.stamp_ns)
    stamps = np.array([ros.stamp_ns(m) for m in wheels], np.int64)
    counts = np.array([np.asarray(m.position) for m in wheels], np.float64).astype(np.int64)
    ticks = np.diff(counts, axis=0, prepend=counts[:1])
    pan_tilt = [
        (ros.stamp_ns(m), np.asarray(m.position, np.float32)) for m in by_topic[topics.PAN_TILT]
    ]
    return RecordedLog(
        path=path,
        model=model,
        episode=episode,
        initial_pose=initial_pose,
        initial_cov=initial_cov,
        stamps=stamps,
        ticks=ticks,
        frames=sorted(frames, key=lambda f: f[0]),
        pan_tilt=sorted(pan_tilt, key=lambda p: p[0]),
        sonar=_sonar(by_topic.get(topics.SONAR, [])),
        aided={ros.stamp_ns(m): m for m in by_topic.get(topics.AIDED, [])},
        truth=_poses_at(by_topic.get(topics.TRUTH, []), stamps),
        topics=frozenset(topic for topic, messages in by_topic.items() if messages),
        end=json.loads(by_topic[topics.EPISODE_END][0].data)
        if by_topic[topics.EPISODE_END]
        else {},
        estimates={
            topic.split("/")[2]: _poses_and_covs(messages)
            for topic, messages in by_topic.items()
            if topic.startswith("/estimate/")
        },
    )


def _json(by_topic: dict[str, list], topic: str, path: Path) -> dict:
    """The JSON mapping of ``topic``'s first message, or a :class:`ConfigError` naming it."""
    try:
        data = json.loads(by_topic[topic][0].data)
    except json.JSONDecodeError as err:
        raise ConfigError(f"{path} {topic}: not JSON ({err})") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path} {topic}: must be a JSON object, got {data!r}")
    return data


def _sonar(messages: list) -> list[tuple[int, np.ndarray]]:
    """The ranges of each sonar scan, by stamp."""
    scans = [(ros.stamp_ns(m), np.asarray(m.ranges, np.float32)) for m in messages]
    return sorted(scans, key=lambda scan: scan[0])


def _poses_at(messages: list, stamps: np.ndarray) -> np.ndarray | None:
    """The poses at exactly the step stamps (None when any step has none)."""
    poses = {ros.stamp_ns(m): ros.planar_pose(m)[0] for m in messages}
    if not all(int(s) in poses for s in stamps):
        return None
    return np.array([poses[int(s)] for s in stamps])


def _poses_and_covs(messages: list) -> tuple[np.ndarray, np.ndarray]:
    decoded = [ros.planar_pose(m) for m in sorted(messages, key=ros.stamp_ns)]
    return np.array([d[0] for d in decoded]), np.array([d[1] for d in decoded])
