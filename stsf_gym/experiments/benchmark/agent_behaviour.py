"""What an agent does where it matters, read from its recorded episodes: how it approaches and
declares a stop, how far it leaves the route, how often it has a board in view, its collisions.

A learnt agent and a script that reach the same success rate may get there differently; a
reviewer asking "what did the agent learn?" wants these beside the success rate, on the same
worlds. Every measure comes from an :class:`~stsf_gym.experiments.episodes.EpisodeResult`
(true poses, estimates and covariances at every 0.1 s control step; the declared stops):

- **at each declared stop**: the true distance to the goal (m), and the estimate's position
  standard deviation there (the cautious follower's measure, the largest axis of the
  position block of its covariance, m): an agent that waits for the estimate to settle
  declares at a smaller one;
- **the approach**: the time from first coming within :data:`APPROACH_M` (true, straight line)
  of where it stopped to the declaration (s), and its mean speed over the last
  :data:`APPROACH_M` driven (m/s): slowing down or waiting near a goal shows in both;
- **leaving the route**: the largest true distance from the world's path over the episode
  (m), where an agent that goes to see a board goes;
- **boards in view**: the share of camera frames with a board wholly in view (true camera
  pose); ``None`` with the camera off;
- **collisions**: the episode ended on touching a wall or an obstacle.
"""

from __future__ import annotations

import numpy as np

from stsf_gym.agents.cautious_follower import position_sigma
from stsf_gym.experiments.episodes import full_covariances
from stsf_gym.results import stat

APPROACH_M = 1.0  # the last metre before a stop: the follower's cruise speed covers it in 8 s

STOP_MEASURES = ("stop_distance_m", "stop_sigma_m", "approach_time_s", "approach_speed_mps")
EPISODE_MEASURES = ("largest_path_distance_m", "boards_in_view_share", "collision")


def record_at(times: np.ndarray, time: float) -> int:
    """The index of the last record at or before ``time``."""
    return max(int(np.searchsorted(times, time, side="right")) - 1, 0)


def stop_measures(episode, stop: dict) -> dict[str, float]:
    """The measures of one declared ``stop`` of ``episode`` (see the module)."""
    times, travelled = np.asarray(episode.times), np.asarray(episode.travelled)
    true_xy = np.asarray(episode.true_poses)[:, :2]
    at = record_at(times, stop["time"])
    near = np.hypot(*(true_xy[: at + 1] - true_xy[at]).T) <= APPROACH_M
    arrived = at - int(np.argmin(near[::-1])) + 1 if not near.all() else 0
    before = travelled[at] - APPROACH_M
    start = record_at(travelled, before) if before > 0 else 0
    span = times[at] - times[start]
    return {
        "stop_distance_m": float(stop["true_distance_m"]),
        "stop_sigma_m": position_sigma(full_covariances(episode.covariances[at])),
        "approach_time_s": float(times[at] - times[arrived]),
        "approach_speed_mps": float((travelled[at] - travelled[start]) / span) if span else 0.0,
    }


def episode_behaviour(episode) -> dict:
    """Every measure of ``episode``: lists over its declared stops, numbers over the episode."""
    stops = [stop_measures(episode, stop) for stop in episode.stops]
    frames = episode.camera_frames
    return {
        **{name: [s[name] for s in stops] for name in STOP_MEASURES},
        "largest_path_distance_m": float(max(episode.path_errors)),
        "boards_in_view_share": episode.frames_in_view / frames if frames else None,
        "collision": episode.outcome == "collision",
        "success": episode.outcome == "goal",
    }


def behaviour_row(behaviours: list[dict]) -> dict:
    """An agent's measures over its episodes: each a ``{mean, std, count, values}`` (stop
    measures over every declared stop)."""
    return {
        "episodes": len(behaviours),
        **{name: stat(v for b in behaviours for v in b[name]) for name in STOP_MEASURES},
        **{name: stat(b[name] for b in behaviours) for name in (*EPISODE_MEASURES, "success")},
    }
