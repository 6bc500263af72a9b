"""Videos: the writer (MP4, GIF without an encoder, atomic), and Gymnasium's RecordVideo on
every registered id."""

import gymnasium as gym
import imageio_ffmpeg
import numpy as np
import pytest
from gymnasium.wrappers import RecordVideo
from helpers import id_matrix, registered_ids
from PIL import Image

import stsf_gym
from stsf_gym.video import VideoWriter


def _frames(count: int = 12) -> list[np.ndarray]:
    frames = []
    for i in range(count):
        frame = np.zeros((48, 64, 3), np.uint8)
        frame[:, 4 * i : 4 * i + 8] = (250, 40, 40)  # a red bar moving right
        frames.append(frame)
    return frames


def _read_mp4(path) -> list[np.ndarray]:
    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    width, height = meta["size"]
    return [np.frombuffer(f, np.uint8).reshape(height, width, 3) for f in reader]


@pytest.mark.parametrize("mp4", [True, False])
def test_writer_round_trip(tmp_path, mp4):
    with VideoWriter(tmp_path / "clip", fps=10, mp4=mp4) as video:
        for frame in _frames():
            video.append(frame)
    assert video.path.name == ("clip.mp4" if mp4 else "clip.gif")
    assert [p.name for p in tmp_path.iterdir()] == [video.path.name]  # no temporary left
    if mp4:
        decoded = _read_mp4(video.path)
    else:
        gif = Image.open(video.path)
        decoded = []
        for i in range(gif.n_frames):
            gif.seek(i)
            decoded.append(np.asarray(gif.convert("RGB")))
    assert len(decoded) == 12
    for frame, back in zip(_frames(), decoded, strict=True):
        assert np.abs(frame.astype(int) - back).mean() < 8  # lossy, but the same picture


def test_interrupted_writer_leaves_no_file(tmp_path):
    with pytest.raises(KeyboardInterrupt), VideoWriter(tmp_path / "clip", fps=10) as video:
        video.append(_frames()[0])
        raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("env_id", id_matrix(registered_ids()))
def test_record_video_on_every_registered_id(tmp_path, env_id):
    assert stsf_gym.ENV_WORLDS  # the ids are registered by the import
    env = gym.make(env_id, render_mode="rgb_array", sim__max_episode_seconds=1.0)
    folder = tmp_path / "videos"
    env = RecordVideo(env, str(folder), episode_trigger=lambda episode: True, disable_logger=True)
    try:
        env.reset(seed=0)
        first = env.render()
        done, steps = False, 0
        while not done:
            _, _, terminated, truncated, _ = env.step(np.zeros(env.action_space.shape, np.float32))
            done, steps = terminated or truncated, steps + 1
    finally:
        env.close()
    (video,) = folder.glob("*.mp4")
    frames = _read_mp4(video)
    # the reset and a frame a step: 10 control steps of 0.1 s, or 2 decisions of 0.5 s on an
    # RL-ready id (moviepy may drop one)
    assert steps in (2, 10) and len(frames) in (steps, steps + 1)
    assert np.abs(frames[0].astype(int) - first).mean() < 6  # the map, not a wall
