"""``stsf-gym reproduce fig10|fig11``: the paper's navigation experiments over many seeds.

- Fig. 10: the straight 10 m at 12.2 cm/s, odometry against STSF (EKF as the reference):
  final and largest error per axis, and the largest error once 5 m have been driven.
- Fig. 11: the IRL corridor with odometry, conventional fusion, STSF and EKF: success, where
  odometry fails, errors along the path and in its latter part, landmark match rates.

Both are evaluations (:mod:`stsf_gym.experiments.evaluate`) of the path follower driving
on each estimate, with the paper's figures beside ours.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from stsf_gym.experiments.episodes import EpisodeResult
from stsf_gym.experiments.evaluate import evaluate
from stsf_gym.experiments.reports import write_report
from stsf_gym.experiments.statistics import mean_std
from stsf_gym.io import markdown_table

FIG10_PAPER = {
    "odometry": "about 0.40 m off after 10 m; max 0.212 m in x, 0.405 m in y",
    "stsf": "0.20-0.30 m until 4 m, below 0.10 m from 5 m on",
}
FIG11_PAPER = {
    "odometry": "collides with the wall at about 17 m",
    "conventional": "reaches the goal; error grows along the path",
    "stsf": "reaches the goal; smallest error in the latter part; match rate about 22 % higher",
}
LATTER_PART_M = 12.0
#: The paper's navigation experiments measure localisation: the follower drives on the pose
#: alone, without the sonar avoidance that would steer a lost robot off the walls.
PATH_ONLY = {"avoidance": {"enabled": False}}


def _axis_errors(episode: EpisodeResult) -> np.ndarray:
    return np.abs(np.array(episode.estimate_xy) - np.array(episode.true_xy))


def fig10(out: Path, seeds: int, seed: int = 0, workers: int = 2, env: dict | None = None):
    summary, by_estimator = evaluate(
        out,
        ["odometry", "stsf", "ekf"],
        seeds,
        seed,
        "straight_10m",
        workers=workers,
        env=env,
        agent_options=PATH_ONLY,
    )
    rows = []
    for name in ("odometry", "stsf", "ekf"):
        episodes = by_estimator[name]
        axis = [_axis_errors(e) for e in episodes]
        after5 = [
            max(
                (err for err, d in zip(e.errors, e.travelled, strict=True) if d >= 5.0),
                default=np.nan,
            )
            for e in episodes
        ]
        rows.append(
            {
                "estimator": name,
                "final x error (m)": mean_std([a[-1, 0] for a in axis]),
                "final y error (m)": mean_std([a[-1, 1] for a in axis]),
                "max x error (m)": mean_std([a[:, 0].max() for a in axis]),
                "max y error (m)": mean_std([a[:, 1].max() for a in axis]),
                "max error after 5 m (m)": mean_std(after5),
                "paper": FIG10_PAPER.get(name, "-"),
            }
        )
    return _write(out, "fig10", "Fig. 10: straight 10 m at 12.2 cm/s", summary, rows)


def fig11(out: Path, seeds: int, seed: int = 0, workers: int = 2, env: dict | None = None):
    names = ["odometry", "conventional", "stsf", "ekf"]
    summary, by_estimator = evaluate(
        out, names, seeds, seed, "irl_corridor", workers=workers, env=env, agent_options=PATH_ONLY
    )
    rows = []
    for name, row in zip(names, summary["rows"], strict=True):
        episodes = by_estimator[name]
        latter = [
            np.mean(
                [err for err, d in zip(e.errors, e.travelled, strict=True) if d >= LATTER_PART_M]
                or [np.nan]
            )
            for e in episodes
        ]
        rows.append(
            {
                "estimator": name,
                "reached goal": f"{row['success rate']:.0%}",
                "collisions": row["collisions"],
                "distance before failure (m)": row["distance before failure (m)"],
                f"mean error after {LATTER_PART_M:g} m (m)": mean_std(latter),
                "RMS heading error (deg)": row["RMS heading error (deg)"],
                "landmark in view": row["landmark in view"],
                "landmark match rate": row["landmark match rate"],
                "NEES (95% bounds)": f"{row['NEES']:.2f} ({row['NEES 95% bounds']})",
                "paper": FIG11_PAPER.get(name, "-"),
            }
        )
    return _write(out, "fig11", "Fig. 11: navigation along the IRL corridor", summary, rows)


def _write(out: Path, name: str, title: str, summary: dict, rows: list[dict]) -> dict:
    summary = {**summary, "paper_rows": rows}
    body = f"{markdown_table(rows)}\n## All metrics\n\n{markdown_table(summary['rows'])}"
    write_report(out, summary, title, body, f"{name}.json", f"{name}.md")
    return summary
