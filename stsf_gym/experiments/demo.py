"""``stsf-gym demo``: the main job. The path follower drives the IRL corridor once with each
estimator (odometry, conventional fusion, STSF, EKF) on its own pose estimate, without sonar
avoidance as in the paper's Fig. 11; a short table and the trajectories over the map, in about
a minute on two cores.
"""

from __future__ import annotations

from pathlib import Path

from stsf_gym.experiments.evaluate import evaluate
from stsf_gym.experiments.figures import PATH_ONLY

DEMO_ESTIMATORS = ["odometry", "conventional", "stsf", "ekf"]
#: The columns of the terminal table (a rendering of ``results.json``'s rows).
COLUMNS = [
    "estimator",
    "success_rate",
    "collision_rate",
    "ate_rmse_m",
    "final_error_m",
    "max_error_m",
    "rms_heading_error_deg",
    "nees_mean",
    "match_rate",
]


def run_demo(out: str | Path, seed: int = 0, workers: int = 2, env: dict | None = None) -> dict:
    """One episode per estimator on the IRL corridor; results.md/json, trajectories.png,
    errors.png, nees.png."""
    summary, _ = evaluate(
        out,
        DEMO_ESTIMATORS,
        1,
        seed,
        "irl_corridor",
        workers=workers,
        env=env,
        agent_options=PATH_ONLY,
    )
    return summary
