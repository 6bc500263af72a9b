"""``stsf-gym reproduce fig10|fig11``: the paper's navigation experiments over many seeds.

- Fig. 10: the straight 10 m at 12.2 cm/s, odometry against STSF (EKF as the reference):
  final and largest error per axis, and the largest error once 5 m have been driven.
- Fig. 11: the IRL corridor under the paper's camera (profile ``paper``) with odometry, the
  paper's conventional fusion (current pair only), the conventional filter, STSF and EKF:
  success, where odometry fails, position and orientation error curves along the path (in the
  JSON too), the error in the latter part (after :data:`LATTER_PART_M`) and landmark match
  rates: the share of camera frames in which the estimator matched at least one map landmark
  it could measure, with STSF's relative to the paper conventional's.

Both are evaluations (:mod:`stsf_gym.experiments.evaluate`) of the path follower driving
on each estimate, with the paper's figures beside ours.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from stsf_gym.config_files import deep_merge
from stsf_gym.experiments.episodes import EpisodeResult
from stsf_gym.experiments.evaluate import evaluate
from stsf_gym.experiments.reports import write_report
from stsf_gym.experiments.result_tables import results_tables
from stsf_gym.experiments.statistics import error_curves
from stsf_gym.io import markdown_table
from stsf_gym.results import rendered, stat

FIG10_PAPER = {
    "odometry": "about 0.40 m off after 10 m; max 0.212 m in x, 0.405 m in y",
    "stsf": "0.20-0.30 m until 4 m, below 0.10 m from 5 m on",
}
FIG11_PAPER = {
    "odometry": "collides with the wall at about 17 m",
    "conventional": "reaches the goal; error grows along the path",
    "stsf": "reaches the goal; smallest error in the latter part; match rate about 22 % higher",
}
#: The paper's Fig. 11 claims as numbers: reached the goal (1) or not (0), where odometry
#: stopped (m), STSF's landmark match rate relative to conventional fusion's (+22 %).
FIG11_PAPER_NUMBERS = {
    "odometry": {"paper_success": 0.0, "paper_distance_before_failure_m": 17.0},
    "conventional": {"paper_success": 1.0},
    "stsf": {"paper_success": 1.0, "paper_match_rate_vs_conventional": 0.22},
}
FIG11_ESTIMATORS = [
    "odometry",
    "conventional",
    "conventional-filter",
    "stsf",
    "ekf",
    "smoother",
    "mcl",
]
#: Fig. 11 runs under the paper's camera whatever the defaults (``--set`` may still change it).
PAPER_CAMERA = {"camera": {"profile": "paper"}}
LATTER_PART_M = 12.0
CURVE_STEP_M = 0.5  # grid of the error curves in the JSON
#: The paper's navigation experiments measure localisation: the follower drives on the pose
#: alone, without the sonar avoidance that would steer a lost robot off the walls.
PATH_ONLY = {"avoidance": {"enabled": False}}

#: The consistency columns of both figures: the time-averaged NEES against its own bounds, and
#: the share of steps inside the per-step bounds.
NEES_KEYS = ("nees_time_average", "nees_time_bounds", "nees_in_bounds")

HEADERS = {
    "final_x_error_m": "final x error (m)",
    "final_y_error_m": "final y error (m)",
    "max_x_error_m": "max x error (m)",
    "max_y_error_m": "max y error (m)",
    "max_error_after_5m_m": "max error after 5 m (m)",
    "mean_error_after_12m_m": f"mean error after {LATTER_PART_M:g} m (m)",
    "mean_heading_error_after_12m_deg": f"mean heading error after {LATTER_PART_M:g} m (deg)",
    "match_rate_vs_conventional": "match rate vs conventional",
}


def _axis_errors(episode: EpisodeResult) -> np.ndarray:
    return np.abs(episode.estimate_xy - episode.true_xy)


def _after(episode: EpisodeResult, distance: float) -> np.ndarray:
    """Position errors once ``distance`` metres have been driven."""
    return episode.errors[np.asarray(episode.travelled) >= distance]


#: The paper's figures keep the paper's reach-the-goal protocol (``task.protocol: reach``: the
#: true pose entering the goal circle ends the episode as a success), whatever the config says.
REACH = {"task": {"protocol": "reach"}}


def fig10(out: Path, seeds: int, seed: int = 0, workers: int = 2, env: dict | None = None):
    """The paper's Fig. 10: odometry, STSF and the EKF along the straight 10 m under the reach
    protocol; writes ``out/fig10`` and returns its summary.
    """
    env = deep_merge(env or {}, REACH)
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
    for name, row in zip(("odometry", "stsf", "ekf"), summary["rows"], strict=True):
        episodes = by_estimator[name]
        axis = [_axis_errors(e) for e in episodes]
        rows.append(
            {
                "estimator": name,
                "final_x_error_m": stat(a[-1, 0] for a in axis),
                "final_y_error_m": stat(a[-1, 1] for a in axis),
                "max_x_error_m": stat(a[:, 0].max() for a in axis),
                "max_y_error_m": stat(a[:, 1].max() for a in axis),
                "max_error_after_5m_m": stat(_maximum(_after(e, 5.0)) for e in episodes),
                **{key: row[key] for key in NEES_KEYS},
                "paper": FIG10_PAPER.get(name, "-"),
            }
        )
    return _write(out, "fig10", "Fig. 10: straight 10 m at 12.2 cm/s", summary, rows)


def fig11(out: Path, seeds: int, seed: int = 0, workers: int = 2, env: dict | None = None):
    """The paper's Fig. 11: every estimator of :data:`FIG11_ESTIMATORS` along the IRL corridor under
    the paper's camera and the reach protocol; writes ``out/fig11`` and returns its summary.
    """
    names = FIG11_ESTIMATORS
    env = deep_merge(deep_merge(PAPER_CAMERA, env or {}), REACH)
    summary, by_estimator = evaluate(
        out, names, seeds, seed, "irl_corridor", workers=workers, env=env, agent_options=PATH_ONLY
    )
    match = {row["estimator"]: row["match_rate"]["mean"] for row in summary["rows"]}
    rows = []
    for name, row in zip(names, summary["rows"], strict=True):
        latter = [_after(e, LATTER_PART_M) for e in by_estimator[name]]
        late_heading = [_heading_after(e, LATTER_PART_M) for e in by_estimator[name]]
        rows.append(
            {
                "estimator": name,
                **{
                    key: row[key]
                    for key in ("success_rate", "collision_rate", "distance_before_failure_m")
                },
                "mean_error_after_12m_m": stat(a.mean() if a.size else None for a in latter),
                "mean_heading_error_after_12m_deg": stat(late_heading),
                "match_rate_vs_conventional": _relative(match[name], match["conventional"]),
                **{
                    key: row[key]
                    for key in (
                        "ate_rmse_m",
                        "floor_ate_m",
                        "ate_vs_floor",
                        "rms_heading_error_deg",
                        "landmark_in_view",
                        "match_rate",
                        *NEES_KEYS,
                    )
                },
                "paper": FIG11_PAPER.get(name, "-"),
                **FIG11_PAPER_NUMBERS.get(name, {}),
            }
        )
    summary["error_curves"] = _error_curves(by_estimator)
    return _write(out, "fig11", "Fig. 11: navigation along the IRL corridor", summary, rows)


def _heading_after(episode: EpisodeResult, distance: float) -> float | None:
    """Mean absolute heading error (deg) once ``distance`` metres have been driven."""
    late = np.asarray(episode.heading_errors)[np.asarray(episode.travelled) >= distance]
    return float(np.degrees(np.abs(late)).mean()) if late.size else None


def _relative(value: float | None, reference: float | None) -> float | None:
    """``value / reference - 1`` (None when either is missing or the reference is 0)."""
    if value is None or not reference:
        return None
    return value / reference - 1.0


def _error_curves(by_estimator: dict[str, list[EpisodeResult]]) -> dict:
    """Mean position (m) and orientation (deg) error on a grid of distance driven, per
    estimator (null where no episode got that far): the numbers behind ``errors.png``."""
    longest = max(e.travelled[-1] for episodes in by_estimator.values() for e in episodes)
    grid = np.arange(0.0, longest + CURVE_STEP_M, CURVE_STEP_M)
    curves: dict = {"distance_m": grid.tolist()}
    for name, episodes in by_estimator.items():
        position, heading = error_curves(episodes, grid)
        curves[name] = {"position_m": _numbers(position), "orientation_deg": _numbers(heading)}
    return curves


def _numbers(values: np.ndarray) -> list[float | None]:
    return [float(v) if np.isfinite(v) else None for v in values]


def _maximum(values: np.ndarray) -> float | None:
    return float(values.max()) if values.size else None


def _write(out: Path, name: str, title: str, summary: dict, rows: list[dict]) -> dict:
    summary = {**summary, "protocol": "reach", "paper_rows": rows}
    title += " (the paper's reach-the-goal protocol)"
    paper = markdown_table([rendered(row, headers=HEADERS) for row in rows])
    every = results_tables(summary["rows"]).replace("\n## ", "\n### ")
    body = f"{paper}\n## All metrics\n\n{every}"
    made_by = summary["provenance"]  # the evaluation's: same episodes, same configuration
    write_report(
        out,
        summary,
        title,
        body,
        f"{name}.json",
        f"{name}.md",
        config=made_by["config"],
        seeds=made_by["seeds"],
    )
    return summary
