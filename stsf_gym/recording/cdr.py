"""The CDR bytes of the messages a recording writes every control step, packed directly.

``rosbags`` serializes any message, through message objects; at five messages a step that
costs a recorded episode several per cent of its wall time, so the per-step ones are packed
here with ``struct`` into exactly the bytes ``rosbags`` writes (little-endian CDR with its
4-byte encapsulation header; every field aligned to its size from the end of that header;
``tests/recording/test_recording.py`` compares the two byte for byte).
"""

from __future__ import annotations

import math
import struct

import numpy as np

from stsf_gym.recording.ros_messages import (
    DETECTION_POINT,
    PLANAR,
    POINT_FIELD_TYPES,
    quaternion_of,
)

ENCAPSULATION = b"\x00\x01\x00\x00"  # CDR, little-endian


class _Buffer:
    def __init__(self) -> None:
        self.parts: list[bytes] = []
        self.size = 0

    def put(self, data: bytes, alignment: int = 1) -> None:
        pad = -self.size % alignment
        if pad:
            self.parts.append(b"\x00" * pad)
        self.parts.append(data)
        self.size += pad + len(data)

    def string(self, text: str) -> None:
        data = text.encode() + b"\x00"
        self.put(struct.pack("<I", len(data)), 4)
        self.put(data)

    def sequence(self, values: np.ndarray, dtype: str) -> None:
        values = np.asarray(values, dtype)
        self.put(struct.pack("<I", len(values)), 4)
        if len(values):
            self.put(values.tobytes(), values.itemsize)

    def header(self, stamp: int, frame_id: str) -> None:
        sec, nanosec = divmod(int(stamp), 1_000_000_000)
        self.put(struct.pack("<iI", sec, nanosec), 4)
        self.string(frame_id)

    def bytes(self) -> bytes:
        return ENCAPSULATION + b"".join(self.parts)


def pose_with_covariance(stamp: int, frame_id: str, pose, cov) -> bytes:
    """``geometry_msgs/PoseWithCovarianceStamped`` of a planar pose and its 3x3 covariance."""
    x, y, yaw = (float(v) for v in pose)
    full = np.zeros((6, 6))
    full[PLANAR] = cov
    b = _Buffer()
    b.header(stamp, frame_id)
    b.put(struct.pack("<7d", x, y, 0.0, 0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)), 8)
    b.put(full.astype("<f8").tobytes(), 8)
    return b.bytes()


def joint_state(stamp: int, frame_id: str, names: tuple[str, ...], positions) -> bytes:
    """``sensor_msgs/JointState`` with positions only."""
    b = _Buffer()
    b.header(stamp, frame_id)
    b.put(struct.pack("<I", len(names)), 4)
    for name in names:
        b.string(name)
    b.sequence(positions, "<f8")
    b.sequence([], "<f8")
    b.sequence([], "<f8")
    return b.bytes()


def sonar_scan(stamp: int, frame_id: str, ranges, axes: np.ndarray, limits) -> bytes:
    """``sensor_msgs/LaserScan`` of a sonar ring (as :func:`.ros_messages.sonar_scan`)."""
    axes = np.asarray(axes, float)
    increment = float(axes[1] - axes[0]) if len(axes) > 1 else 0.0
    b = _Buffer()
    b.header(stamp, frame_id)
    fields = (axes[0], axes[-1], increment, 0.0, 0.0, limits[0], limits[1])
    b.put(struct.pack("<7f", *fields), 4)
    b.sequence(ranges, "<f4")
    b.sequence([], "<f4")
    return b.bytes()


def twist(stamp: int, frame_id: str, linear: float, angular: float) -> bytes:
    """``geometry_msgs/TwistStamped``: forward speed and yaw rate."""
    b = _Buffer()
    b.header(stamp, frame_id)
    b.put(struct.pack("<6d", linear, 0.0, 0.0, 0.0, 0.0, angular), 8)
    return b.bytes()


def tf_message(stamp: int, transforms: list[tuple[str, str, np.ndarray]]) -> bytes:
    """``tf2_msgs/TFMessage`` of ``(parent, child, 4x4 parent-from-child)`` transforms."""
    b = _Buffer()
    b.put(struct.pack("<I", len(transforms)), 4)
    for parent, child, matrix in transforms:
        b.header(stamp, parent)
        b.string(child)
        matrix = np.asarray(matrix, float)
        b.put(struct.pack("<7d", *matrix[:3, 3], *quaternion_of(matrix[:3, :3])), 8)
    return b.bytes()


def detection_cloud(stamp: int, frame_id: str, points: np.ndarray) -> bytes:
    """``sensor_msgs/PointCloud2`` of :data:`.ros_messages.DETECTION_POINT` rows."""
    points = np.ascontiguousarray(points, DETECTION_POINT)
    b = _Buffer()
    b.header(stamp, frame_id)
    b.put(struct.pack("<III", 1, len(points), len(DETECTION_POINT.names)), 4)
    for name in DETECTION_POINT.names:
        dtype, offset = DETECTION_POINT.fields[name]
        b.string(name)
        b.put(struct.pack("<I", offset), 4)
        b.put(struct.pack("<B", POINT_FIELD_TYPES[dtype.str]))
        b.put(struct.pack("<I", 1), 4)
    b.put(struct.pack("<B", 0))  # is_bigendian
    b.put(struct.pack("<II", points.itemsize, points.itemsize * len(points)), 4)
    b.sequence(points.view(np.uint8).ravel(), "<u1")
    b.put(struct.pack("<B", 0))  # is_dense: NaN padding
    return b.bytes()


def restamped(data: bytes, stamp: int) -> bytes:
    """A serialized message that starts with its header, with that header's stamp set."""
    sec, nanosec = divmod(int(stamp), 1_000_000_000)
    return data[:4] + struct.pack("<iI", sec, nanosec) + data[12:]
