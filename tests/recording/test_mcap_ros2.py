"""The MCAP log as ROS 2 tools take it, read back with the ``mcap`` reader: every channel offers
the QoS profile rosbag2 records (``/tf_static`` transient-local, so ``ros2 bag play`` latches
it; the rest volatile), and the file is in time order (log times never decrease, chunks do not
overlap in time), with the fast mode's detections and with rendered frames (several chunks)."""

from __future__ import annotations

from itertools import pairwise
from pathlib import Path

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from rosbags.interfaces import QosDurability, QosReliability
from rosbags.rosbag2.metadata import parse_qos

from stsf_gym.episode_env import make_episode_env
from stsf_gym.recording import qos, topics
from stsf_gym.recording import ros_messages as ros
from stsf_gym.recording.mcap_writer import McapLogWriter
from stsf_gym.recording.wrapper import RecordEpisode
from stsf_gym.validation import ConfigError

#: Camera settings -> the episode's length (s): fast-mode detections, and rendered raw frames
#: long enough to fill several 1 MiB chunks.
CAMERAS = {"fast": ({"camera": {"mode": "fast"}}, 6.0), "frames": ({}, 2.0)}


@pytest.fixture(scope="module", params=sorted(CAMERAS))
def log(request, tmp_path_factory) -> tuple[str, Path]:
    """The camera's name and a recorded episode of STSF driving straight on with it."""
    settings, seconds = CAMERAS[request.param]
    env = make_episode_env(
        "irl_corridor", "stsf", {**settings, "sim": {"max_episode_seconds": seconds}}
    )
    recorded = RecordEpisode(env, tmp_path_factory.mktemp(request.param))
    recorded.reset(seed=3)
    done = False
    while not done:
        *_, terminated, truncated, _ = recorded.step(np.array([0.6, 0.0], np.float32))
        done = terminated or truncated
    recorded.close()
    return request.param, recorded.paths[0]


def test_each_channel_offers_the_qos_rosbag2_records(log):
    _, path = log
    with path.open("rb") as f:
        channels = make_reader(f).get_summary().channels.values()
    topics_seen = {channel.topic for channel in channels}
    assert {topics.TF_STATIC, topics.TF, topics.WHEEL_TICKS} <= topics_seen
    for channel in channels:
        text = channel.metadata[qos.METADATA_KEY]
        (profile,) = yaml.safe_load(text)
        assert profile == qos.offered_profile(channel.topic), channel.topic
        (read,) = parse_qos(text)  # rosbags reads it as rosbag2 does
        latched = channel.topic == topics.TF_STATIC
        expected = QosDurability.TRANSIENT_LOCAL if latched else QosDurability.VOLATILE
        assert read.durability == expected, channel.topic
        assert read.reliability == QosReliability.RELIABLE, channel.topic


def test_log_times_never_decrease_and_chunks_do_not_overlap(log):
    camera, path = log
    with path.open("rb") as f:
        reader = make_reader(f)
        chunks = sorted(reader.get_summary().chunk_indexes, key=lambda c: c.chunk_start_offset)
        in_file = [message.log_time for _, _, message in reader.iter_messages(log_time_order=False)]
    assert in_file == sorted(in_file) and len(in_file) > 100
    for before, after in pairwise(chunks):
        assert before.message_end_time <= after.message_start_time
    if camera == "frames":
        assert len(chunks) >= 2  # the loop above compared chunks


def test_a_stamp_before_the_last_one_is_refused_naming_its_topic(tmp_path):
    log = McapLogWriter(tmp_path / "own.mcap")
    log.write(topics.WHEEL_TICKS, 2_000, ros.joint_state(2_000, topics.WHEELS, [0, 0]))
    with pytest.raises(ConfigError, match=f"{topics.WHEEL_TICKS}: stamp 1000 ns is before"):
        log.write(topics.WHEEL_TICKS, 1_000, ros.joint_state(1_000, topics.WHEELS, [0, 0]))
    log.close()
