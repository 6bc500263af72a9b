"""A log from outside is input: every topic a pose source reads is present or the replay is
refused naming it; every number of its sensor model and episode passes a config's checks;
"approximate" is decided by the frames' bytes, never by a claim in the episode file."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from helpers import load_script

from stsf_gym.recording import ros_messages as ros
from stsf_gym.recording import topics
from stsf_gym.recording.log_reader import read_log
from stsf_gym.recording.mcap_writer import McapLogWriter
from stsf_gym.recording.sensor_model_json import sensor_model_dict

DT, STEPS = 0.1, 6


def _own_robot():
    """``examples/own_robot_log.py``: a hand-written sensor model of a robot of one's own."""
    return load_script("examples/own_robot_log.py")


def write_log(
    path: Path,
    model: dict | None = None,
    episode: dict | None = None,
    camera: str | None = "detections",
    pan_tilt: bool = True,
) -> Path:
    """A short log of a robot standing still: ``camera`` frames as ``detections``, ``png``,
    ``jpeg`` (the bytes of that format) or none; ``model`` keys over the example's model."""
    document = sensor_model_dict(_own_robot().sensor_model())
    document.update(model or {})
    log = McapLogWriter(path)
    log.write(topics.SENSOR_MODEL, 0, ros.string(json.dumps(document)))
    log.write(topics.EPISODE, 0, ros.string(json.dumps({"control_dt": DT, **(episode or {})})))
    start = np.zeros(3)
    log.write(topics.INITIAL_POSE, 0, ros.pose_with_covariance(0, "map", start, np.eye(3) * 1e-4))
    grey = np.full((240, 320, 3), 90, np.uint8)
    for k in range(STEPS):
        stamp = round(k * DT * 1e9)
        log.write(topics.WHEEL_TICKS, stamp, ros.joint_state(stamp, topics.WHEELS, [0, 0]))
        log.write(
            topics.TRUTH, stamp, ros.pose_with_covariance(stamp, "map", start, np.zeros((3, 3)))
        )
        if pan_tilt:
            log.write(topics.PAN_TILT, stamp, ros.joint_state(stamp, topics.MOUNT_JOINTS, [0, 0]))
        if camera == "detections":
            empty = ros.detection_slots(np.zeros(0, np.int64), np.zeros((0, 2)))
            log.write(topics.DETECTIONS, stamp, ros.detection_cloud(stamp, empty))
        elif camera is not None:
            data = cv2.imencode(f".{camera}", grey)[1].tobytes()
            claimed = "png" if camera == "jpeg" else "jpeg"  # the format field lies
            log.write(topics.IMAGE_COMPRESSED, stamp, ros.compressed_image(stamp, data, claimed))
    log.close()
    return path


@pytest.mark.parametrize(
    ("log", "estimators", "message"),
    [
        (
            {"camera": None},
            "odometry,stsf",
            "pose source 'stsf' reads the camera, and the log has no",
        ),
        ({"camera": None}, "ekf", "/camera/detections topic"),
        ({"pan_tilt": False}, "stsf", "has no /camera/pan_tilt topic"),
        ({"pan_tilt": False}, "mcl", "pose source 'mcl' reads the camera"),
        ({"episode": {"control_dt": -0.1}}, "odometry", "/robot/episode: control_dt must be > 0"),
        ({"episode": {"control_dt": float("nan")}}, "odometry", "control_dt must be a finite"),
        ({"episode": {"control_dt": None}}, "odometry", "control_dt must be a number, got None"),
        ({"episode": {"seed": -3}}, "odometry", "seed must be >= 0"),
        (
            {
                "model": {
                    "odometry": {
                        "ticks_per_rev": 2048,
                        "wheel_radius_left": -0.05,
                        "wheel_radius_right": 0.05,
                        "wheelbase": 0.3,
                    }
                }
            },
            "odometry",
            "/robot/sensor_model: odometry.wheel_radius_left must be in (0, 10], got -0.05",
        ),
        (
            {"model": {"odometry_noise": {"slip_var_per_m": -1e-5}}},
            "odometry",
            "odometry_noise.slip_var_per_m must be >= 0",
        ),
        ({"model": {"mount": {"x": 0.1, "y": 0.0, "z": 1e308}}}, "odometry", "mount.z must be in"),
        (
            {
                "model": {
                    "camera": {
                        "K": [[-300, 0, 160], [0, 300, 120], [0, 0, 1]],
                        "dist": [0] * 5,
                        "image_size": [320, 240],
                        "calibration_std": [0.002, 0.01],
                    }
                }
            },
            "stsf",
            "camera.K must have focal lengths > 0",
        ),
        (
            {"model": {"walls": [[0, 0, float("inf"), 0]]}},
            "odometry",
            "walls[0][2] must be a finite",
        ),
        ({"model": {"colour": "red"}}, "odometry", "unknown config key 'colour'"),
    ],
)
def test_a_log_lacking_what_a_source_reads_or_with_bad_numbers_is_refused(
    run_cli, tmp_path, log, estimators, message
):
    path = write_log(tmp_path / "theirs.mcap", **log)
    out = tmp_path / "out"
    code, err = run_cli("replay", str(path), "--estimators", estimators, "--out", str(out))
    assert code == 2 and message in err and str(path) in err, err
    assert len(err.strip().splitlines()) == 1 and not out.exists()


def test_odometry_replays_a_log_without_camera_topics(tmp_path):
    from stsf_gym.experiments.replay import replay_logs

    path = write_log(tmp_path / "wheels.mcap", camera=None, pan_tilt=False)
    summary = replay_logs([path], ["odometry"], tmp_path / "out")
    assert [row["estimator"] for row in summary["rows"]] == ["odometry"]


@pytest.mark.parametrize(
    ("camera", "claim", "approximate"),
    [
        ("jpeg", {"lossless": True}, True),  # JPEG bytes, claimed lossless and labelled png
        ("jpeg", {}, True),  # ... or with no claim at all
        ("png", {"lossless": False}, False),  # PNG bytes labelled jpeg, claimed lossy
        ("detections", {"lossless": False}, False),
    ],
)
def test_approximate_is_decided_by_the_frames_bytes(tmp_path, camera, claim, approximate):
    from stsf_gym.experiments.replay import replay_logs

    path = write_log(tmp_path / "frames.mcap", episode=claim, camera=camera)
    assert read_log(path).lossless is not approximate
    summary = replay_logs([path], ["odometry"], tmp_path / "out")
    assert summary["rows"][0]["approximate"] is approximate
