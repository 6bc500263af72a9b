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
COLUMNS = [
    "estimator",
    "success rate",
    "collisions",
    "final error (m)",
    "max error (m)",
    "RMS heading error (deg)",
    "NEES",
    "landmark match rate",
]


def run_demo(out: str | Path, seed: int = 0, workers: int = 2, env: dict | None = None) -> dict:
    """One episode per estimator on the IRL corridor; results.md, trajectories.png, errors.png."""
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
    summary["table"] = [{k: row[k] for k in COLUMNS} for row in summary["rows"]]
    return summary
