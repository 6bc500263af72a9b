"""The log format: topics and their standard ROS 2 message types (see docs/log_format.md).

A replay needs :data:`REQUIRED`, and for a pose source reading the camera camera data (one of
:data:`CAMERA`) and :data:`PAN_TILT` (:data:`SENSOR_TOPICS`); everything else is for looking at
or for scoring. Time is the header stamp (ns, simulated time from 0 for our
recordings); one :data:`WHEEL_TICKS` message is one control step of the estimators.
"""

from __future__ import annotations

SENSOR_MODEL = "/robot/sensor_model"  # std_msgs/String: the SensorModel as JSON, once
EPISODE = "/robot/episode"  # std_msgs/String: JSON {"control_dt", "frames", ...}, once
EPISODE_END = "/robot/episode_end"  # std_msgs/String: JSON {"outcome"}, at the end
INITIAL_POSE = "/initialpose"  # geometry_msgs/PoseWithCovarianceStamped: the start, once
WHEEL_TICKS = "/wheel_ticks"  # sensor_msgs/JointState: cumulative encoder ticks, every step
PAN_TILT = "/camera/pan_tilt"  # sensor_msgs/JointState: mount angles (rad) of each frame
IMAGE_COMPRESSED = "/camera/image/compressed"  # sensor_msgs/CompressedImage: png or jpeg
IMAGE_RAW = "/camera/image"  # sensor_msgs/Image: rgb8
DETECTIONS = "/camera/detections"  # sensor_msgs/PointCloud2: fast-mode detections per frame
AIDED = "/camera/aided_detections"  # sensor_msgs/PointCloud2: what a track-aided search finds
CAMERA_INFO = "/camera/camera_info"  # sensor_msgs/CameraInfo: the believed calibration
SONAR = "/sonar/scan"  # sensor_msgs/LaserScan: the sonar ring, one range each, every step
TRUTH = "/ground_truth/pose"  # geometry_msgs/PoseWithCovarianceStamped: for scoring only
CMD_VEL = "/cmd_vel"  # geometry_msgs/TwistStamped: the agent's command (m/s, rad/s)
TF, TF_STATIC = "/tf", "/tf_static"  # tf2_msgs/TFMessage: map->base_link (truth), mounts


def estimate_topic(name: str) -> str:
    """``/estimate/<name>/pose`` (PoseWithCovarianceStamped): a pose source's estimate."""
    return f"/estimate/{name}/pose"


TYPES: dict[str, str] = {
    SENSOR_MODEL: "std_msgs/msg/String",
    EPISODE: "std_msgs/msg/String",
    EPISODE_END: "std_msgs/msg/String",
    INITIAL_POSE: "geometry_msgs/msg/PoseWithCovarianceStamped",
    WHEEL_TICKS: "sensor_msgs/msg/JointState",
    PAN_TILT: "sensor_msgs/msg/JointState",
    IMAGE_COMPRESSED: "sensor_msgs/msg/CompressedImage",
    IMAGE_RAW: "sensor_msgs/msg/Image",
    DETECTIONS: "sensor_msgs/msg/PointCloud2",
    AIDED: "sensor_msgs/msg/PointCloud2",
    CAMERA_INFO: "sensor_msgs/msg/CameraInfo",
    SONAR: "sensor_msgs/msg/LaserScan",
    TRUTH: "geometry_msgs/msg/PoseWithCovarianceStamped",
    CMD_VEL: "geometry_msgs/msg/TwistStamped",
    TF: "tf2_msgs/msg/TFMessage",
    TF_STATIC: "tf2_msgs/msg/TFMessage",
}
ESTIMATE_TYPE = "geometry_msgs/msg/PoseWithCovarianceStamped"
REQUIRED = (SENSOR_MODEL, EPISODE, INITIAL_POSE, WHEEL_TICKS)
CAMERA = (IMAGE_COMPRESSED, IMAGE_RAW, DETECTIONS)
#: What a pose source reading each sensor (its ``sensors``) needs of a log: one topic with
#: messages out of every group.
SENSOR_TOPICS: dict[str, tuple[tuple[str, ...], ...]] = {
    "encoders": ((WHEEL_TICKS,),),
    "camera": (CAMERA, (PAN_TILT,)),  # frames, and the mount angles they were taken at
}
#: Joint names of the wheel ticks and the mount angles.
WHEELS, MOUNT_JOINTS = ("left_wheel", "right_wheel"), ("camera_pan", "camera_tilt")
#: The frame of the sonar ring: on the robot's axis at the transducers' height.
SONAR_FRAME = "sonar_ring"
#: How camera frames are stored (``--record-frames``): lossless ones replay bit for bit.
FRAME_FORMATS = {"png": True, "raw": True, "jpeg": False}


def type_of(topic: str) -> str:
    """The ROS 2 message type of ``topic``."""
    return ESTIMATE_TYPE if topic.startswith("/estimate/") else TYPES[topic]
