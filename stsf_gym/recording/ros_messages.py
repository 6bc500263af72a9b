"""Standard ROS 2 messages built and read in plain Python, without a ROS install.

``rosbags`` supplies the message types (:data:`TYPESTORE`, ROS 2 Humble's definitions) and
their CDR serialization, so a log holds what ``ros2 bag``, Foxglove and evo expect. Poses are
planar: ``[x, y, yaw]`` is a pose at ``z = 0`` rotated by ``yaw`` about z, its 3x3 covariance
the ``x, y, yaw`` block of ROS's 6x6 (``x, y, z, roll, pitch, yaw``) covariance.

The builders here are what a script writing a log of its own robot uses
(``examples/own_robot_log.py``), and the reference the recorder's packed per-step bytes
(:mod:`.cdr`) are tested against.
"""

from __future__ import annotations

import math

import numpy as np
from rosbags.typesys import Stores, get_typestore

from stsf_gym.validation import ConfigError

TYPESTORE = get_typestore(Stores.ROS2_HUMBLE)
_T = TYPESTORE.types
#: Indices of the x, y, yaw block in ROS's row-major 6x6 pose covariance.
PLANAR = np.ix_([0, 1, 5], [0, 1, 5])


def serialize(message, msgtype: str) -> bytes:
    """CDR bytes of ``message`` of ROS 2 type ``msgtype``."""
    return bytes(TYPESTORE.serialize_cdr(message, msgtype))


def deserialize(data: bytes, msgtype: str):
    """The message of ROS 2 type ``msgtype`` in CDR bytes ``data``."""
    return TYPESTORE.deserialize_cdr(data, msgtype)


def message_definition(msgtype: str) -> str:
    """The ``ros2msg`` schema text of ``msgtype`` with its dependencies (MCAP's schema)."""
    return TYPESTORE.generate_msgdef(msgtype, ros_version=2)[0]


def header(stamp_ns: int, frame_id: str):
    """A ``std_msgs/Header`` at ``stamp_ns`` (ns) in frame ``frame_id``."""
    sec, nanosec = divmod(int(stamp_ns), 1_000_000_000)
    return _T["std_msgs/msg/Header"](
        stamp=_T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec), frame_id=frame_id
    )


def stamp_ns(message) -> int:
    """The header stamp of ``message`` in nanoseconds."""
    return message.header.stamp.sec * 1_000_000_000 + message.header.stamp.nanosec


def string(text: str):
    """A ``std_msgs/String`` holding ``text``."""
    return _T["std_msgs/msg/String"](data=text)


def _quaternion(yaw: float):
    return _T["geometry_msgs/msg/Quaternion"](
        x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)
    )


def _yaw(q) -> float:
    return 2.0 * math.atan2(q.z, q.w)


def pose_with_covariance(stamp: int, frame_id: str, pose, cov):
    """``geometry_msgs/PoseWithCovarianceStamped`` of a planar pose and its 3x3 covariance."""
    x, y, yaw = (float(v) for v in pose)
    full = np.zeros((6, 6))
    full[PLANAR] = cov
    point = _T["geometry_msgs/msg/Point"](x=x, y=y, z=0.0)
    return _T["geometry_msgs/msg/PoseWithCovarianceStamped"](
        header=header(stamp, frame_id),
        pose=_T["geometry_msgs/msg/PoseWithCovariance"](
            pose=_T["geometry_msgs/msg/Pose"](position=point, orientation=_quaternion(yaw)),
            covariance=full.ravel(),
        ),
    )


def planar_pose(message) -> tuple[np.ndarray, np.ndarray]:
    """``([x, y, yaw], 3x3 covariance)`` of a ``PoseWithCovarianceStamped``."""
    pose = message.pose.pose
    mean = np.array([pose.position.x, pose.position.y, _yaw(pose.orientation)])
    return mean, np.asarray(message.pose.covariance, float).reshape(6, 6)[PLANAR]


def quaternion_of(rotation: np.ndarray) -> tuple[float, float, float, float]:
    """``(x, y, z, w)`` of a 3x3 rotation matrix (Shepperd's method: the largest of the four
    squares first, so every rotation is well conditioned)."""
    r = np.asarray(rotation, float)
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    i = int(np.argmax([r[0, 0], r[1, 1], r[2, 2], trace]))
    if i == 3:
        s = 2.0 * math.sqrt(1.0 + trace)
        return ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, s / 4)
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2.0 * math.sqrt(1.0 + r[i, i] - r[j, j] - r[k, k])
    q = [0.0, 0.0, 0.0]
    q[i], q[j], q[k] = s / 4, (r[j, i] + r[i, j]) / s, (r[k, i] + r[i, k]) / s
    return q[0], q[1], q[2], (r[k, j] - r[j, k]) / s


def transform(stamp: int, parent: str, child: str, matrix: np.ndarray):
    """``geometry_msgs/TransformStamped`` of a 4x4 ``parent``-from-``child`` pose."""
    x, y, z, w = quaternion_of(np.asarray(matrix)[:3, :3])
    t = np.asarray(matrix, float)[:3, 3]
    return _T["geometry_msgs/msg/TransformStamped"](
        header=header(stamp, parent),
        child_frame_id=child,
        transform=_T["geometry_msgs/msg/Transform"](
            translation=_T["geometry_msgs/msg/Vector3"](x=t[0], y=t[1], z=t[2]),
            rotation=_T["geometry_msgs/msg/Quaternion"](x=x, y=y, z=z, w=w),
        ),
    )


def tf_message(transforms: list):
    """A ``tf2_msgs/TFMessage`` of ``transforms``."""
    return _T["tf2_msgs/msg/TFMessage"](transforms=transforms)


def joint_state(stamp: int, names: list[str], positions) -> object:
    """A ``sensor_msgs/JointState`` of joint ``positions`` named ``names`` at ``stamp`` (ns)."""
    positions = np.asarray(positions, dtype=np.float64)
    empty = np.zeros(0, np.float64)
    return _T["sensor_msgs/msg/JointState"](
        header=header(stamp, ""), name=list(names), position=positions, velocity=empty, effort=empty
    )


def sonar_scan(stamp: int, frame_id: str, ranges, axes: np.ndarray, limits) -> object:
    """``sensor_msgs/LaserScan`` of a sonar ring: one range per transducer, at headings
    ``axes`` (evenly spaced, counter-clockwise from the first)."""
    axes = np.asarray(axes, float)
    return _T["sensor_msgs/msg/LaserScan"](
        header=header(stamp, frame_id),
        angle_min=float(axes[0]),
        angle_max=float(axes[-1]),
        angle_increment=float(axes[1] - axes[0]) if len(axes) > 1 else 0.0,
        time_increment=0.0,
        scan_time=0.0,
        range_min=float(limits[0]),
        range_max=float(limits[1]),
        ranges=np.asarray(ranges, np.float32),
        intensities=np.zeros(0, np.float32),
    )


def camera_info(stamp: int, K: np.ndarray, dist: np.ndarray, size: tuple[int, int]) -> object:
    """``sensor_msgs/CameraInfo`` of a pinhole camera with OpenCV's (plumb bob) distortion."""
    K = np.asarray(K, dtype=np.float64)
    projection = np.hstack([K, np.zeros((3, 1))])
    return _T["sensor_msgs/msg/CameraInfo"](
        header=header(stamp, "camera_optical"),
        height=int(size[1]),
        width=int(size[0]),
        distortion_model="plumb_bob",
        d=np.asarray(dist, dtype=np.float64),
        k=K.ravel(),
        r=np.eye(3).ravel(),
        p=projection.ravel(),
        binning_x=0,
        binning_y=0,
        roi=_T["sensor_msgs/msg/RegionOfInterest"](
            x_offset=0, y_offset=0, height=0, width=0, do_rectify=False
        ),
    )


def compressed_image(stamp: int, data: bytes, image_format: str) -> object:
    """A ``sensor_msgs/CompressedImage`` (``png`` or ``jpeg``) in the camera's optical frame."""
    return _T["sensor_msgs/msg/CompressedImage"](
        header=header(stamp, "camera_optical"),
        format=image_format,
        data=np.frombuffer(data, np.uint8),
    )


def raw_image(stamp: int, rgb: np.ndarray) -> object:
    """A lossless ``sensor_msgs/Image`` (``rgb8``) in the camera's optical frame."""
    height, width = rgb.shape[:2]
    return _T["sensor_msgs/msg/Image"](
        header=header(stamp, "camera_optical"),
        height=height,
        width=width,
        encoding="rgb8",
        is_bigendian=0,
        step=3 * width,
        data=np.ascontiguousarray(rgb, np.uint8).ravel(),
    )


#: The fields of a detections cloud: pixel x, y (float32: the fast mode's pixels exactly), the
#: detection slot and the landmark id (int32).
DETECTION_POINT = np.dtype([("x", "<f4"), ("y", "<f4"), ("slot", "<i4"), ("landmark_id", "<i4")])
POINT_FIELD_TYPES = {"<f4": 7, "<i4": 5}  # sensor_msgs/PointField FLOAT32, INT32


def detection_cloud(stamp: int, points: np.ndarray) -> object:
    """``sensor_msgs/PointCloud2`` of a :data:`DETECTION_POINT` array (one row per point)."""
    points = np.ascontiguousarray(points, DETECTION_POINT)
    field = _T["sensor_msgs/msg/PointField"]
    fields = [
        field(name=name, offset=offset, datatype=POINT_FIELD_TYPES[dtype.str], count=1)
        for name, (dtype, offset) in DETECTION_POINT.fields.items()
    ]
    return _T["sensor_msgs/msg/PointCloud2"](
        header=header(stamp, "camera_image"),
        height=1,
        width=len(points),
        fields=fields,
        is_bigendian=False,
        point_step=DETECTION_POINT.itemsize,
        row_step=DETECTION_POINT.itemsize * len(points),
        data=points.view(np.uint8).ravel(),
        is_dense=False,
    )


def detection_slots(ids: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The :data:`DETECTION_POINT` rows of the fast mode's slots: ``ids`` (one per slot, -1
    empty) and ``points`` (``x0, y0, x1, y1, ...``, the same count per slot)."""
    ids = np.asarray(ids)
    uv = np.asarray(points, np.float32).reshape(-1, 2)
    per_slot = len(uv) // max(len(ids), 1)
    rows = np.zeros(len(uv), DETECTION_POINT)
    rows["x"], rows["y"] = uv[:, 0], uv[:, 1]
    rows["slot"] = np.repeat(np.arange(len(ids)), per_slot)
    rows["landmark_id"] = np.repeat(ids, per_slot)
    return rows


def slots_of(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(ids, points)`` of :func:`detection_slots` rows (inverse); no rows: one empty slot."""
    if not len(rows):
        return np.full(1, -1, np.int64), np.zeros(2, np.float32)
    ids = np.full(int(rows["slot"].max()) + 1, -1, np.int64)
    ids[rows["slot"]] = rows["landmark_id"]
    return ids, np.column_stack([rows["x"], rows["y"]]).ravel()


def detection_points(message) -> np.ndarray:
    """The :data:`DETECTION_POINT` rows of a :func:`detection_cloud` message."""
    names = [f.name for f in message.fields]
    if names != list(DETECTION_POINT.names) or message.point_step != DETECTION_POINT.itemsize:
        raise ConfigError(
            f"detections need PointCloud2 fields {DETECTION_POINT.names}, got {names}"
        )
    return np.frombuffer(np.asarray(message.data, np.uint8).tobytes(), DETECTION_POINT)


def twist(stamp: int, linear: float, angular: float) -> object:
    """A ``geometry_msgs/TwistStamped`` command: forward speed (m/s) and yaw rate (rad/s)."""
    vector = _T["geometry_msgs/msg/Vector3"]
    return _T["geometry_msgs/msg/TwistStamped"](
        header=header(stamp, "base_link"),
        twist=_T["geometry_msgs/msg/Twist"](
            linear=vector(x=float(linear), y=0.0, z=0.0),
            angular=vector(x=0.0, y=0.0, z=float(angular)),
        ),
    )
