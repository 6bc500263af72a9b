"""A video of episodes already driven: nothing is simulated again. Each episode (one per pose
source, on the same world) gets a panel over the world's map where its true path (green) and
the estimate the agent drove on (red, dashed) grow as recorded, played :data:`SPEED_UP` times
faster than simulated time; a panel whose episode ended keeps its last frame and outcome."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np

from stsf_gym.experiments.episodes import EpisodeResult
from stsf_gym.experiments.plotting.maps import draw_world_config, pyplot
from stsf_gym.video import VideoWriter

#: Playback speed relative to simulated time: a route of about 300 simulated seconds plays
#: in about 15 s.
SPEED_UP = 20.0
FPS = 10.0  # frames per second: a frame every SPEED_UP / FPS = 2 simulated seconds


def frame_times(episodes: list[EpisodeResult], speed_up: float = SPEED_UP) -> np.ndarray:
    """The simulated times of the frames: from 0 every ``speed_up / FPS`` seconds, and the
    longest episode's end."""
    end = max(e.times[-1] for e in episodes)
    times = np.arange(0.0, end, speed_up / FPS)
    return np.append(times, end)


def episode_frames(
    by_source: dict[str, EpisodeResult], speed_up: float = SPEED_UP
) -> Iterator[np.ndarray]:
    """RGB frames of the episodes side by side (see the module's docstring)."""
    from stsf_gym.envs.generated_env import episode_world

    plt = pyplot()
    episodes = list(by_source.values())
    fig, axes = plt.subplots(1, len(episodes), figsize=(3.2 * len(episodes), 3.4), dpi=80)
    axes = np.atleast_1d(axes)
    panels = []
    for ax, (name, episode) in zip(axes, by_source.items(), strict=True):
        spec = episode.spec
        draw_world_config(ax, episode_world(spec["world"], spec["seed"], spec["env"]))
        ax.set_xlabel("")
        ax.set_ylabel("")
        (true_line,) = ax.plot([], [], color="tab:green", lw=1.5)
        (estimate_line,) = ax.plot([], [], color="tab:red", ls="--", lw=1.2)
        ax.set_title(name, fontsize=9)
        status = ax.text(0.02, 0.02, "", transform=ax.transAxes, fontsize=8)
        panels.append((status, true_line, estimate_line))
    fig.tight_layout()
    fig.canvas.draw()  # the map once; each frame draws only the lines and status (blitting)
    background = fig.canvas.copy_from_bbox(fig.bbox)
    paths = [(np.asarray(e.true_xy), np.asarray(e.estimate_xy)) for e in episodes]
    try:
        for now in frame_times(episodes, speed_up):
            fig.canvas.restore_region(background)
            for episode, (status, true_line, estimate_line), (true, estimate) in zip(
                episodes, panels, paths, strict=True
            ):
                upto = int(np.searchsorted(episode.times, now, side="right"))
                true_line.set_data(*true[:upto].T)
                estimate_line.set_data(*estimate[:upto].T)
                ended = upto >= len(episode.times)
                status.set_text(episode.outcome if ended else f"{now:.0f} s")
                for artist in (status, true_line, estimate_line):
                    artist.axes.draw_artist(artist)
            yield np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()
    finally:
        plt.close(fig)


def record_episodes_video(
    by_source: dict[str, list[EpisodeResult]], stem: str | Path, speed_up: float = SPEED_UP
) -> Path:
    """``stem.mp4`` (``stem.gif`` without an encoder) of the first episode of each pose source
    (:func:`episode_frames`); returns the file."""
    first = {name: episodes[0] for name, episodes in by_source.items()}
    with VideoWriter(stem, FPS) as video:
        for frame in episode_frames(first, speed_up):
            video.append(frame)
    return video.path
