"""Recordings read back with their own readers (MCAP's, Rerun's, evo's), and estimators replayed
on a recorded log exactly as they ran live."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from collections import Counter
from pathlib import Path

import cv2
import gymnasium as gym
import numpy as np
import pytest
from helpers import ROOT
from mcap.reader import make_reader

from stsf_gym.agents.registry import make_agent
from stsf_gym.episode_env import make_episode_env
from stsf_gym.recording import ros_messages as ros
from stsf_gym.recording import topics
from stsf_gym.recording.log_reader import read_log
from stsf_gym.recording.replay import replay
from stsf_gym.recording.sensor_model_json import sensor_model_dict, sensor_model_from_dict
from stsf_gym.recording.wrapper import RecordEpisode, make_recorder
from stsf_gym.validation import ConfigError
from stsf_gym.wrappers import PoseEstimateWrapper, sensor_model

FAST = {"camera": {"mode": "fast"}}


def record(folder: Path, estimator: str, seconds: float, env: dict, **recording):
    """Drive the follower for ``seconds`` with ``estimator``, recorded; return the wrapper, the
    live estimates and covariances at every step, the observations and the infos."""
    inner = make_episode_env(
        "irl_corridor", estimator, {**env, "sim": {"max_episode_seconds": seconds}}
    )
    env = RecordEpisode(inner, folder, name_prefix=estimator, **recording)
    obs, info = env.reset(seed=5)
    follower = make_agent("follower")
    follower.begin(env)
    act = follower.act
    live = inner.get_wrapper_attr  # the estimator: a new object after a late frame
    means, covs = [live("estimator").mean.copy()], [live("estimator").cov.copy()]
    history = [(obs, info)]
    done = False
    while not done:
        obs, _, terminated, truncated, info = env.step(act(obs))
        means.append(live("estimator").mean.copy())
        covs.append(live("estimator").cov.copy())
        history.append((obs, info))
        done = terminated or truncated
    env.close()
    return env, np.array(means), np.array(covs), history


@pytest.fixture(scope="module")
def fast_log(tmp_path_factory):
    return record(tmp_path_factory.mktemp("fast"), "stsf", 6.0, FAST)


def test_the_sensor_model_survives_json_exactly(make_env):
    env = PoseEstimateWrapper(make_env(camera__mode="fast"), "odometry")
    env.reset(seed=2)
    model = sensor_model(env)
    back = sensor_model_from_dict(json.loads(json.dumps(sensor_model_dict(model))))
    assert back.calibration == model.calibration
    assert back.odometry_noise == model.odometry_noise
    assert np.array_equal(back.camera_calibration.K, model.camera_calibration.K)
    assert np.array_equal(back.camera_calibration.dist, model.camera_calibration.dist)
    assert back.landmarks.keys() == model.landmarks.keys()
    for key, landmark in model.landmarks.items():
        assert np.array_equal(back.landmarks[key].square_centres, landmark.square_centres)
    for pan, tilt in [(0.0, 0.0), (0.4, -0.1), (-1.2, 0.3)]:
        live = env.unwrapped.robot_from_camera(pan, tilt)
        assert np.array_equal(back.robot_from_camera(pan, tilt), live)
    with pytest.raises(ValueError, match="missing config key 'walls'"):
        sensor_model_from_dict({k: v for k, v in sensor_model_dict(model).items() if k != "walls"})


def test_the_mcap_log_reads_back_with_the_mcap_reader(fast_log):
    env, _, _, history = fast_log
    (path,) = env.paths
    assert path.name == "stsf.mcap"
    counts, types, stamps, truth = Counter(), {}, {}, []
    with path.open("rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            counts[channel.topic] += 1
            types[channel.topic] = schema.name
            stamps.setdefault(channel.topic, []).append(message.log_time)
            if channel.topic == topics.TRUTH:
                truth.append(ros.planar_pose(ros.deserialize(message.data, schema.name))[0])
    steps = len(history)
    frames = sum(int(obs["image_new"]) for obs, _ in history)
    assert counts[topics.WHEEL_TICKS] == counts[topics.TRUTH] == steps
    assert counts[topics.SONAR] == steps
    assert counts[topics.DETECTIONS] == counts[topics.CAMERA_INFO] == frames > 0
    assert counts[topics.CMD_VEL] == steps - 1
    assert counts[topics.estimate_topic("stsf")] == steps
    assert types[topics.TRUTH] == "geometry_msgs/msg/PoseWithCovarianceStamped"
    assert types[topics.SONAR] == "sensor_msgs/msg/LaserScan"
    assert types[topics.TF] == "tf2_msgs/msg/TFMessage"
    assert types[topics.CAMERA_INFO] == "sensor_msgs/msg/CameraInfo"
    times = [round(info["sim_time"] * 1e9) for _, info in history]
    assert stamps[topics.WHEEL_TICKS] == times
    final = history[-1][1]["true_pose"]
    assert np.allclose(truth[-1], final, atol=1e-12)


def test_a_recorded_episode_replays_bit_for_bit(fast_log):
    env, means, covs, history = fast_log
    log = read_log(env.paths[0])
    assert log.lossless
    for replayed, (live, _) in zip(log.observations(), history, strict=True):
        for key in ("encoders", "image_new", "camera_pan_tilt", "sonar"):
            assert np.array_equal(replayed[key], live[key]), key
            assert np.asarray(replayed[key]).dtype == np.asarray(live[key]).dtype, key
        for key in ("landmark", "aided"):
            assert np.array_equal(replayed[f"{key}_ids"], live[f"{key}_ids"]), key
            assert np.array_equal(replayed[f"{key}_points"], live[f"{key}_points"], equal_nan=True)
    run = replay(log, "stsf")
    assert np.array_equal(run.means, means)
    assert np.array_equal(run.covs, covs)
    assert run.counters["frames"] > 0


@pytest.mark.parametrize("estimator", ["stsf", "ekf"])
def test_an_episode_with_camera_latency_replays_bit_for_bit(tmp_path, estimator):
    """Late frames are fused at their exposure on replay as they were live (the history)."""
    latency = {"camera": {"mode": "fast", "latency": {"profile": "paper"}}}
    env, means, covs, history = record(tmp_path, estimator, 8.0, latency)
    late = [obs for obs, _ in history if obs["image_time"][0] < obs["encoders_time"][0] - 1e-6]
    assert any(obs["image_new"] for obs in late)  # frames did arrive late
    run = replay(read_log(env.paths[0]), estimator)
    assert run.counters["frames_late"] > 0 and run.counters["landmark_updates"] > 0
    assert np.array_equal(run.means, means)
    assert np.array_equal(run.covs, covs)


@pytest.mark.parametrize("frames", ["raw", "png"])
def test_rendered_frames_lossless_exact_and_jpeg_approximate(tmp_path, frames):
    env, means, _, history = record(tmp_path, "ekf", 3.0, {}, frames=frames)
    log = read_log(env.paths[0])
    first_frame = next(obs for obs, _ in history[1:] if obs["image_new"])
    replayed = next(obs for obs in list(log.observations())[1:] if obs["image_new"])
    assert np.array_equal(replayed["image"], first_frame["image"])
    assert np.array_equal(replay(log, "ekf").means, means)
    jpeg_env, _, _, _ = record(tmp_path / "jpeg", "ekf", 3.0, {}, frames="jpeg")
    jpeg_log = read_log(jpeg_env.paths[0])
    assert not jpeg_log.lossless
    with jpeg_log.path.open("rb") as f:
        compressed = next(
            ros.deserialize(m.data, s.name)
            for s, c, m in make_reader(f).iter_messages(topics=[topics.IMAGE_COMPRESSED])
        )
    assert compressed.format == "jpeg"
    decoded = cv2.imdecode(np.asarray(compressed.data), cv2.IMREAD_COLOR)
    assert decoded.shape == first_frame["image"].shape


def test_quaternions_of_rotation_matrices():
    from scipy.spatial.transform import Rotation

    for rotation in Rotation.random(200, random_state=1):
        ours, theirs = np.array(ros.quaternion_of(rotation.as_matrix())), rotation.as_quat()
        assert min(abs(ours - theirs).max(), abs(ours + theirs).max()) < 1e-12


@pytest.mark.slow
def test_the_rerun_recording_reads_back(tmp_path):
    from rerun.chunk import RrdReader

    env, means, _, history = record(tmp_path, "stsf", 4.0, FAST, fmt="rerun")
    (path,) = env.paths
    assert path.suffix == ".rrd"
    rows, static, timelines, errors = Counter(), Counter(), set(), {}
    for chunk in RrdReader(path).stream():
        (static if chunk.is_static else rows)[chunk.entity_path] += chunk.num_rows
        timelines.update(chunk.timeline_names)
        if chunk.entity_path == "/metrics/position_error/stsf":
            batch = chunk.to_record_batch().to_pydict()
            for t, value in zip(batch["sim_time"], batch["Scalars:scalars"], strict=True):
                errors[t] = value[0]
    steps = len(history)
    assert "sim_time" in timelines
    for entity in ("world/truth", "world/estimate/stsf", "world/sonar", "metrics/nees/stsf"):
        assert rows[f"/{entity}"] == steps, entity
    assert rows["/agent/action/v"] == steps - 1
    assert static["/world/walls"] == static["/world/landmarks"] == 1
    assert static["/world/trajectory/truth"] == static["/world/trajectory/stsf"] == 1
    assert rows["/camera/detections"] == sum(int(obs["image_new"]) for obs, _ in history)
    truth = np.array([info["true_pose"] for _, info in history])
    expected = np.hypot(*(means[:, :2] - truth[:, :2]).T)
    assert np.allclose([errors[t] for t in sorted(errors)], expected, rtol=1e-12, atol=1e-15)
    script = ROOT / "examples" / "plot_recording.py"
    picture = tmp_path / "recording.png"
    subprocess.run([sys.executable, str(script), str(path), "--out", str(picture)], check=True)
    assert picture.stat().st_size > 10_000


def test_the_wrapper_records_its_arguments_and_changes_nothing(make_env, tmp_path):
    plain = PoseEstimateWrapper(make_env(camera__mode="fast"), "odometry")
    recorded = RecordEpisode(
        PoseEstimateWrapper(make_env(camera__mode="fast"), "odometry"), tmp_path, "mcap"
    )
    assert recorded.spec.additional_wrappers[-1].kwargs["fmt"] == "mcap"
    for env in (plain, recorded):
        env.reset(seed=1)
    for _ in range(15):
        a, *_ = plain.step(np.float32([0.6, 0.1]))
        b, *_ = recorded.step(np.float32([0.6, 0.1]))
        assert all(np.array_equal(a[k], b[k]) for k in a)
    recorded.close()
    registered = RecordEpisode(gym.make("stsf_gym/Corridor-v0", camera__mode="fast"), tmp_path)
    registered.reset(seed=0)
    registered.step(np.float32([0.5, 0.0]))
    registered.close()
    log = read_log(registered.paths[0])
    assert len(log.stamps) == 2 and not log.estimates  # no pose source in that stack


def test_the_packed_per_step_messages_are_rosbags_bytes():
    from scipy.spatial.transform import Rotation

    from stsf_gym.recording import cdr

    rng = np.random.default_rng(0)
    axes = np.arange(16) * 2 * np.pi / 16
    for _ in range(20):
        stamp, pose, a = int(rng.integers(0, 10**12)), rng.normal(size=3), rng.normal(size=(3, 3))
        ticks, ranges = rng.normal(size=2) * 1e3, rng.random(16).astype(np.float32)
        for frame in ("map", "", "sonar_ring"):
            pairs = [
                (
                    cdr.pose_with_covariance(stamp, frame, pose, a @ a.T),
                    ros.pose_with_covariance(stamp, frame, pose, a @ a.T),
                ),
                (
                    cdr.sonar_scan(stamp, frame, ranges, axes, (0.1, 4.0)),
                    ros.sonar_scan(stamp, frame, ranges, axes, (0.1, 4.0)),
                ),
            ]
            for packed, message in pairs:
                assert packed == ros.serialize(message, message.__msgtype__)
        packed = cdr.joint_state(stamp, "", topics.WHEELS, ticks)
        message = ros.joint_state(stamp, topics.WHEELS, ticks)
        assert packed == ros.serialize(message, message.__msgtype__)
        message = ros.twist(stamp, 0.3, -0.2)
        assert cdr.twist(stamp, "base_link", 0.3, -0.2) == ros.serialize(
            message, message.__msgtype__
        )
        matrix = np.eye(4)
        matrix[:3, :3] = Rotation.random(random_state=int(rng.integers(1000))).as_matrix()
        matrix[:3, 3] = rng.normal(size=3)
        message = ros.tf_message([ros.transform(stamp, "map", "camera", matrix)])
        packed = cdr.tf_message(stamp, [("map", "camera", matrix)])
        assert packed == ros.serialize(message, message.__msgtype__)
        points = np.zeros(int(rng.integers(0, 60)), ros.DETECTION_POINT)
        points["x"], points["landmark_id"] = rng.normal(size=len(points)), 7
        message = ros.detection_cloud(stamp, points)
        packed = cdr.detection_cloud(stamp, "camera_image", points)
        assert packed == ros.serialize(message, message.__msgtype__)
        info = ros.camera_info(0, np.diag([300.0, 300.0, 1.0]), rng.normal(size=5), (320, 240))
        serialized = ros.serialize(info, info.__msgtype__)
        info.header = ros.header(stamp, info.header.frame_id)
        assert cdr.restamped(serialized, stamp) == ros.serialize(info, info.__msgtype__)


def test_recording_without_its_extra_names_it(monkeypatch, tmp_path):
    """A core install (no ``record`` extra) asked to record says which extra it needs."""
    find_spec = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "rerun" else find_spec(name)
    )
    message = r"--record rerun needs the recording extra \(rerun not installed\): pip install"
    with pytest.raises(ConfigError, match=message):
        make_recorder(tmp_path / "episode.rrd", "rerun")
