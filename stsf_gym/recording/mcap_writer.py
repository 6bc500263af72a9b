"""An episode as an MCAP file of standard ROS 2 messages (:mod:`.topics`), written without ROS.

Foxglove, ``ros2 bag`` (with the MCAP storage plugin) and evo (``evo_ape bag2 FILE.mcap
/ground_truth/pose /estimate/stsf/pose``) open it. It holds all an estimator needs, so
``stsf-gym replay`` reruns any pose source on it: with lossless frames (raw, the default, or
PNG) bit for bit; JPEG frames are smaller and for looking at.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import cv2
import numpy as np
from mcap.writer import CompressionType, Writer

from stsf_gym.camera_model import rot_z
from stsf_gym.io import create_temporary
from stsf_gym.recording import cdr, qos, topics
from stsf_gym.recording import ros_messages as ros
from stsf_gym.recording.records import EpisodeStart, StepRecord, nanoseconds
from stsf_gym.recording.sensor_model_json import sensor_model_json
from stsf_gym.validation import ConfigError

JPEG_QUALITY = 90
PNG_COMPRESSION = 1  # zlib level: the fastest that compresses


class McapLogWriter:
    """An MCAP file of ROS 2 messages on the log's topics (:mod:`.topics`), written atomically
    (a temporary file renamed at :meth:`close`): ``write(topic, stamp_ns, message)`` with a
    message from :mod:`.ros_messages`. What a plain script uses to write a log of its own
    robot (``examples/own_robot_log.py``).

    Each channel carries the QoS profile rosbag2 would have recorded (:mod:`.qos`), and messages
    go in in time order (a stamp before the last one is refused), so the log times never
    decrease through the file and its chunks do not overlap in time."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        fd, self._tmp = create_temporary(self.path, "")
        self._file = os.fdopen(fd, "wb")
        self._writer = Writer(self._file, compression=CompressionType.ZSTD)
        self._writer.start(profile="ros2", library="stsf-gym")
        self._channels: dict[str, int] = {}
        self._schemas: dict[str, int] = {}
        self._last_stamp = 0

    def write(self, topic: str, stamp: int, message) -> None:
        """Serialize ``message`` with its topic's ROS 2 type and write it at ``stamp`` (ns)."""
        self.write_cdr(topic, stamp, ros.serialize(message, topics.type_of(topic)))

    def write_cdr(self, topic: str, stamp: int, data: bytes) -> None:
        """Write a message already serialized (:mod:`.cdr`)."""
        if stamp < self._last_stamp:
            raise ConfigError(
                f"{topic}: stamp {stamp} ns is before the last message written "
                f"({self._last_stamp} ns); write a log's messages in time order"
            )
        self._last_stamp = stamp
        if topic not in self._channels:
            msgtype = topics.type_of(topic)
            if msgtype not in self._schemas:
                definition = ros.message_definition(msgtype).encode()
                self._schemas[msgtype] = self._writer.register_schema(
                    msgtype, "ros2msg", definition
                )
            self._channels[topic] = self._writer.register_channel(
                topic, "cdr", self._schemas[msgtype], qos.channel_metadata(topic)
            )
        self._writer.add_message(self._channels[topic], stamp, data, stamp)

    @property
    def closed(self) -> bool:
        return self._file.closed

    def close(self) -> None:
        """Finish the MCAP file and move it to its name (atomic); a second call does nothing."""
        if self._file.closed:
            return
        self._writer.finish()
        self._file.close()
        os.replace(self._tmp, self.path)


class McapRecorder:
    """Writes one episode to ``path`` (:class:`McapLogWriter`); camera frames as ``frames``:
    ``"raw"`` (``sensor_msgs/Image``, lossless; the MCAP's chunks are zstd-compressed), ``"png"``
    (lossless, a little smaller, far slower to encode) or ``"jpeg"`` (lossy, about 8x smaller)."""

    def __init__(self, path: str | Path, frames: str = "raw") -> None:
        if frames not in topics.FRAME_FORMATS:
            raise ConfigError(
                f"frames must be one of {sorted(topics.FRAME_FORMATS)}, got {frames!r}"
            )
        self.frames = frames
        self.log = McapLogWriter(path)
        self.path = self.log.path
        self._write = self.log.write
        self._ticks = np.zeros(2, np.int64)
        self._layout, self._last_stamp = None, 0

    def start(self, start: EpisodeStart) -> None:
        """Write the episode's sensor model, camera info, metadata and the start pose."""
        self._layout, self._model = start.layout, start.model
        calibration = start.model.camera_calibration
        info = ros.camera_info(0, calibration.K, calibration.dist, start.model.image_size)
        self._camera_info = ros.serialize(info, topics.type_of(topics.CAMERA_INFO))
        lossless = topics.FRAME_FORMATS[self.frames]
        episode = {
            **start.meta,
            "control_dt": start.control_dt,
            "frames": self.frames,
            "lossless": lossless,
        }
        self._write(topics.SENSOR_MODEL, 0, ros.string(sensor_model_json(start.model)))
        self._write(topics.EPISODE, 0, ros.string(json.dumps(episode)))
        initial = ros.pose_with_covariance(0, "map", start.initial_pose, start.initial_cov)
        self._write(topics.INITIAL_POSE, 0, initial)
        ring = np.eye(4)
        ring[2, 3] = start.layout.sonar_height
        sonar = ros.transform(0, "base_link", topics.SONAR_FRAME, ring)
        self._write(topics.TF_STATIC, 0, ros.tf_message([sonar]))

    def step(self, record: StepRecord) -> None:
        """Write one step: wheel ticks, mount, sonar, the frame or detections, poses, command."""
        stamp, obs, layout = nanoseconds(record.time), record.obs, self._layout
        self._last_stamp = stamp
        self._ticks = self._ticks + np.asarray(obs["encoders"], np.int64)
        write = self.log.write_cdr
        write(topics.WHEEL_TICKS, stamp, cdr.joint_state(stamp, "", topics.WHEELS, self._ticks))
        if obs["image_new"] or record.action is None:  # the robot's TF at frames and the start
            self._transforms(stamp, record)
        if obs["image_new"]:
            self._frame(stamp, record)
        scan = cdr.sonar_scan(
            stamp, topics.SONAR_FRAME, obs["sonar"], layout.sonar_axes, layout.sonar_limits
        )
        write(topics.SONAR, stamp, scan)
        truth = cdr.pose_with_covariance(stamp, "map", record.true_pose, np.zeros((3, 3)))
        write(topics.TRUTH, stamp, truth)
        for name, (mean, cov) in record.estimates.items():
            write(
                topics.estimate_topic(name),
                stamp,
                cdr.pose_with_covariance(stamp, "map", mean, cov),
            )
        if record.action is not None:
            v, w = np.clip(np.asarray(record.action, float).ravel()[:2], -1, 1)
            command = cdr.twist(stamp, "base_link", v * layout.max_speed, w * layout.max_yaw_rate)
            write(topics.CMD_VEL, stamp, command)

    def _transforms(self, stamp: int, record: StepRecord) -> None:
        """``map -> base_link`` (the true pose) and ``base_link -> camera_optical`` (the mount
        at the frame's angles), at the camera's rate (TF consumers interpolate)."""
        base = np.eye(4)
        base[:3, :3] = rot_z(record.true_pose[2])
        base[:2, 3] = record.true_pose[:2]
        pan_tilt = np.asarray(record.obs["camera_pan_tilt"], np.float64)
        mount = self._model.robot_from_camera(*pan_tilt)
        transforms = [("map", "base_link", base), ("base_link", "camera_optical", mount)]
        self.log.write_cdr(topics.TF, stamp, cdr.tf_message(stamp, transforms))

    def _frame(self, stamp: int, record: StepRecord) -> None:
        """The frame that arrived at ``stamp`` (the log time), its header stamped with its
        exposure (earlier when the camera has a latency)."""
        obs, write = record.obs, self.log.write_cdr
        exposure = nanoseconds(float(obs["image_time"][0]))
        pan_tilt = np.asarray(obs["camera_pan_tilt"], np.float64)
        write(topics.PAN_TILT, stamp, cdr.joint_state(stamp, "", topics.MOUNT_JOINTS, pan_tilt))
        write(topics.CAMERA_INFO, stamp, cdr.restamped(self._camera_info, exposure))
        if "image" in obs:
            self._image(stamp, exposure, obs["image"])
        else:
            slots = [(topics.DETECTIONS, "landmark")]
            if "aided_ids" in obs:  # the boards a track-aided search would find
                slots.append((topics.AIDED, "aided"))
            for topic, key in slots:
                points = ros.detection_slots(obs[f"{key}_ids"], obs[f"{key}_points"])
                write(topic, stamp, cdr.detection_cloud(exposure, "camera_image", points))

    def _image(self, stamp: int, exposure: int, rgb: np.ndarray) -> None:
        if self.frames == "raw":
            self._write(topics.IMAGE_RAW, stamp, ros.raw_image(exposure, rgb))
            return
        bgr = cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR)
        if self.frames == "png":
            ok, data = cv2.imencode(".png", bgr, [cv2.IMWRITE_PNG_COMPRESSION, PNG_COMPRESSION])
        else:
            ok, data = cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
        if not ok:
            raise RuntimeError(f"could not encode a camera frame as {self.frames}")
        self._write(
            topics.IMAGE_COMPRESSED,
            stamp,
            ros.compressed_image(exposure, data.tobytes(), self.frames),
        )

    def close(self, end: dict | None = None) -> None:
        """Write the episode's ending (when given) and finish the file."""
        if self.log.closed:
            return
        if end is not None:
            self._write(topics.EPISODE_END, self._last_stamp, ros.string(json.dumps(end)))
        self.log.close()
