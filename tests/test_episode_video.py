"""Demo videos show the whole episode, sped up: a frame every ``SPEED_UP / FPS`` simulated
seconds from the start to the episode's last step."""

from itertools import pairwise

import imageio_ffmpeg
import pytest

from stsf_gym.experiments.episode_video import FPS, SPEED_UP, episode_frames, record_episode
from stsf_gym.experiments.episodes import EpisodeSpec, run_episode
from stsf_gym.video import mp4_available

SHORT = {"sim": {"max_episode_seconds": 4.0}, "camera": {"mode": "fast"}}


def _spec() -> EpisodeSpec:
    return EpisodeSpec("irl_corridor", "odometry", 0, env=SHORT)


def test_frames_run_from_the_start_to_the_episodes_end():
    times = [t for t, _ in episode_frames(_spec())]
    end = run_episode(_spec()).sim_time  # the same episode, driven without a camera on it
    assert times[0] == 0.0
    assert times[-1] == pytest.approx(end)
    period = SPEED_UP / FPS
    gaps = [b - a for a, b in pairwise(times)]
    assert all(period - 0.1 - 1e-6 <= gap < period + 0.1 + 1e-6 for gap in gaps[:-1])
    assert 0 < gaps[-1] < period + 0.2  # the last step shows even between two frames


def test_seconds_cut_the_episode_short():
    times = [t for t, _ in episode_frames(_spec(), seconds=1.5, speed_up=6.0)]
    assert times == pytest.approx([0.0, 0.3, 0.6, 0.9, 1.2, 1.5])  # 0.3 s a frame at 20 fps


@pytest.mark.skipif(not mp4_available(), reason="no MP4 encoder")
def test_the_video_holds_every_frame(tmp_path):
    path = record_episode(_spec(), tmp_path / "odometry")
    reader = imageio_ffmpeg.read_frames(str(path))
    next(reader)
    assert sum(1 for _ in reader) == len(list(episode_frames(_spec())))
