"""``stsf-gym demo``: the main job. The path follower drives the IRL corridor once with each
estimator (odometry, conventional fusion as the paper has it and as a filter, STSF, EKF) on its
own pose estimate, without sonar avoidance as in the paper's Fig. 11; a short table, the
trajectories over the map and a video of each episode's whole route, ten times faster than
simulated time (``videos/<estimator>.mp4``; each video drives its episode again, to its end).
"""

from __future__ import annotations

from pathlib import Path

from stsf_gym.episode_env import estimator_options
from stsf_gym.experiments.episode_video import record_videos
from stsf_gym.experiments.episodes import EpisodeSpec
from stsf_gym.experiments.evaluate import evaluate
from stsf_gym.experiments.figures import PATH_ONLY

DEMO_ESTIMATORS = ["odometry", "conventional", "conventional-filter", "stsf", "ekf"]
#: The columns of the terminal table (a rendering of ``results.json``'s rows).
COLUMNS = [
    "estimator",
    "success_rate",
    "collision_rate",
    "time_limit_rate",
    "ate_rmse_m",
    "final_error_m",
    "max_error_m",
    "rms_heading_error_deg",
    "nees_mean",
    "match_rate",
]


def run_demo(
    out: str | Path,
    seed: int = 0,
    workers: int = 2,
    env: dict | None = None,
    video_seconds: float | None = None,
    seeds: int = 1,
    record: dict | None = None,
    backend: str = "local",
    address: str | None = None,
) -> dict:
    """``seeds`` episodes per estimator on the IRL corridor; results.md/json, trajectories.png,
    errors.png, nees.png and, unless ``video_seconds`` is 0, a video of each estimator's first
    episode in ``videos/``, the whole of it (or its first ``video_seconds``); with ``record``
    each episode recorded (:func:`~stsf_gym.experiments.episodes.run_episode`). The episodes
    run in ``workers`` local processes or as Ray tasks (``backend``, ``address``); the videos
    locally."""
    summary, _ = evaluate(
        out,
        DEMO_ESTIMATORS,
        seeds,
        seed,
        "irl_corridor",
        workers=workers,
        env=env,
        agent_options=PATH_ONLY,
        record=record,
        backend=backend,
        address=address,
    )
    if video_seconds is None or video_seconds > 0:
        specs = [
            EpisodeSpec(
                "irl_corridor", e, seed, "follower", env or {}, estimator_options(e), PATH_ONLY
            )
            for e in DEMO_ESTIMATORS
        ]
        videos = record_videos(specs, Path(out) / "videos", video_seconds, workers)
        summary["videos"] = {e: f"videos/{name}" for e, name in videos.items()}
    return summary
