"""The demo's video is made from episodes already driven: a frame every ``SPEED_UP / FPS``
simulated seconds from the start to the longest episode's end, a panel per pose source."""

from itertools import pairwise

import imageio_ffmpeg
import pytest

from stsf_gym.experiments.episode_video import (
    FPS,
    SPEED_UP,
    episode_frames,
    frame_times,
    record_episodes_video,
)
from stsf_gym.experiments.episodes import EpisodeSpec, run_episode
from stsf_gym.video import mp4_available

FAST = {"camera": {"mode": "fast"}}


@pytest.fixture(scope="module")
def episodes():
    """Two episodes of different lengths on the same world."""
    return {
        name: run_episode(
            EpisodeSpec("irl_corridor", name, 0, env={**FAST, "sim": {"max_episode_seconds": s}})
        )
        for name, s in (("odometry", 30.0), ("ekf", 50.0))
    }


def test_frames_run_from_the_start_to_the_longest_episodes_end(episodes):
    times = frame_times(list(episodes.values()))
    assert times[0] == 0.0
    assert times[-1] == pytest.approx(episodes["ekf"].sim_time)
    gaps = [b - a for a, b in pairwise(times)]
    assert all(gap == pytest.approx(SPEED_UP / FPS) for gap in gaps[:-1])
    assert 0 < gaps[-1] <= SPEED_UP / FPS


def test_one_panel_per_pose_source_and_the_lines_grow(episodes):
    frames = list(episode_frames(episodes))
    assert len(frames) == len(frame_times(list(episodes.values())))
    first, last = frames[0], frames[-1]
    assert (
        first.shape == last.shape and first.shape[1] > 1.5 * first.shape[0]
    )  # two panels side by side
    green = (last[..., 1] > 100) & (last[..., 0] < 100) & (last[..., 2] < 100)
    before = (first[..., 1] > 100) & (first[..., 0] < 100) & (first[..., 2] < 100)
    assert green.sum() > before.sum() + 50  # the true path (green) drawn by the end


@pytest.mark.skipif(not mp4_available(), reason="no MP4 encoder")
def test_the_video_holds_every_frame(episodes, tmp_path):
    path = record_episodes_video({k: [v] for k, v in episodes.items()}, tmp_path / "demo")
    reader = imageio_ffmpeg.read_frames(str(path))
    next(reader)
    assert sum(1 for _ in reader) == len(frame_times(list(episodes.values())))
