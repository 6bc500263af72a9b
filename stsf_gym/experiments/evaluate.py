"""``stsf-gym evaluate``: an agent driving on each estimator's pose, over seeded episodes.

Writes ``results.json``, ``results.md`` (one row per estimator), ``trajectories.png`` (true
vs estimated paths over the map, with 2-sigma ellipses) and ``errors.png`` (position and
heading error against distance driven). Finished episodes are kept in ``episodes/`` and
reused by a rerun with the same ``--out``. With fault files, every fault set runs on every
estimator instead (:mod:`stsf_gym.experiments.fault_runs`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from scipy.stats import chi2

from envs.config import CONFIG_DIR, read_yaml
from stsf_gym.experiments.episodes import EpisodeResult, EpisodeSpec, run_episodes
from stsf_gym.io import markdown_table, save_figure, write_atomic, write_json


def evaluate(
    out: str | Path,
    estimators: list[str],
    seeds: int,
    seed: int = 0,
    world: str = "irl_corridor",
    agent: str = "follower",
    workers: int = 2,
    env: dict | None = None,
    faults: list[str | Path] | None = None,
    agent_options: dict | None = None,
) -> tuple[dict, dict[str, list[EpisodeResult]]]:
    """Run ``seeds`` episodes per estimator; write the table and figures to ``out``.

    Returns the summary (as written to results.json) and the episodes per estimator. With
    ``faults`` (fault files), the episodes run per fault set and estimator instead.
    """
    if faults:
        from stsf_gym.experiments.fault_runs import evaluate_faults

        return evaluate_faults(
            out, estimators, seeds, seed, world, agent, workers, env or {}, faults
        )
    out = Path(out)
    specs = [
        EpisodeSpec(
            world, estimator, s, agent, env or {}, estimator_options(estimator), agent_options or {}
        )
        for estimator in estimators
        for s in range(seed, seed + seeds)
    ]
    results = run_episodes(specs, out / "episodes", workers, desc=f"evaluate {world}")
    by_estimator = {e: [r for r in results if r.spec["estimator"] == e] for e in estimators}
    rows = [summarise(name, episodes) for name, episodes in by_estimator.items()]
    summary = {"world": world, "agent": agent, "seeds": [seed, seed + seeds - 1], "rows": rows}
    title = agent
    if agent != "follower":  # a saved model: record what it was trained on
        from agents.sb3_agent import training_record

        summary["trained"] = training_record(agent)
        title += " ({algo} trained on {estimator}, {timesteps} steps)".format(**summary["trained"])
    write_json(out / "results.json", summary)
    write_atomic(out / "results.md", f"# Evaluation: {title} on {world}\n\n" + markdown_table(rows))
    summary["figures"] = [
        str(plot_trajectories(world, by_estimator, out / "trajectories.png")),
        str(plot_errors(by_estimator, out / "errors.png")),
    ]
    return summary, by_estimator


def estimator_options(name: str) -> dict:
    """The options in ``configs/estimators/<name>.yaml``, recorded with every episode."""
    path = CONFIG_DIR / "estimators" / f"{name}.yaml"
    return read_yaml(path) if path.is_file() else {}


def summarise(estimator: str, episodes: list[EpisodeResult]) -> dict:
    """One table row: success, failures, errors, consistency, landmark matching, timing."""
    final = [e.errors[-1] for e in episodes]
    rms = [math.sqrt(np.mean(np.square(e.errors))) for e in episodes]
    worst = [max(e.errors) for e in episodes]
    heading = [math.sqrt(np.mean(np.square(e.heading_errors))) for e in episodes]
    nees_in_bounds, (lo, hi) = nees_consistency(episodes)
    failed = [e.distance for e in episodes if e.outcome != "goal"]
    frames = sum(e.frames for e in episodes)
    stages = sorted({k for e in episodes for k in e.stage_ms_per_step})
    return {
        "estimator": estimator,
        "episodes": len(episodes),
        "success rate": np.mean([e.outcome == "goal" for e in episodes]),
        "collisions": sum(e.outcome == "collision" for e in episodes),
        "distance before failure (m)": float(np.mean(failed)) if failed else "-",
        "final error (m)": _mean_std(final),
        "RMS error (m)": _mean_std(rms),
        "max error (m)": _mean_std(worst),
        "RMS heading error (deg)": _mean_std(np.degrees(heading)),
        "NEES": float(np.mean([e.nees for e in episodes])),
        "NEES 95% bounds": f"{lo:.2f}-{hi:.2f}",
        "NEES in bounds": nees_in_bounds,
        "landmark in view": sum(e.frames_in_view for e in episodes)
        / max(1, sum(e.camera_frames for e in episodes)),
        "landmark match rate": sum(e.frames_matched for e in episodes) / frames if frames else "-",
        "ms per step": ", ".join(
            f"{k} {np.mean([e.stage_ms_per_step.get(k, 0.0) for e in episodes]):.2f}"
            for k in stages
        ),
    }


def nees_consistency(episodes: list[EpisodeResult]) -> tuple[float, tuple[float, float]]:
    """Monte-Carlo NEES test (Bar-Shalom, Li and Kirubarajan 2001, sect. 5.4).

    At each stored sample k, the NEES averaged over the M runs times M is chi-square with 3M
    degrees of freedom for a consistent estimator; returns the fraction of samples (up to the
    shortest run) whose average lies inside the two-sided 95 % bounds, and the bounds. The
    bounds also serve for the time average in the table (time-averaging only narrows the
    spread, so they are conservative for it); samples within a run are correlated, so using
    every step as a degree of freedom would give far too narrow bounds.
    """
    m = len(episodes)
    lo, hi = chi2.ppf([0.025, 0.975], 3 * m) / m
    length = min(len(e.nees_trace) for e in episodes)
    average = np.mean([e.nees_trace[:length] for e in episodes], axis=0)
    return float(np.mean((average >= lo) & (average <= hi))), (float(lo), float(hi))


def _mean_std(values) -> str:
    return f"{np.mean(values):.3f} ± {np.std(values):.3f}"


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_trajectories(world: str, by_estimator: dict, path: Path) -> Path:
    """True and estimated paths of the first episode per estimator, over the map."""
    from stsf_gym.experiments.generated_worlds import episode_world
    from stsf_gym.experiments.plots import draw_world_config

    plt = _pyplot()
    n = len(by_estimator)
    fig, axes = plt.subplots(1, n, figsize=(5 * n, 4.5), squeeze=False)
    for ax, (name, episodes) in zip(axes[0], by_estimator.items(), strict=True):
        episode = episodes[0]
        draw_world_config(ax, episode_world(world, episode.spec["seed"]))
        true_xy, est_xy = np.array(episode.true_xy), np.array(episode.estimate_xy)
        ax.plot(*true_xy.T, color="tab:green", label="true")
        ax.plot(*est_xy.T, color="tab:red", ls="--", label="estimate")
        for xy, cov in list(zip(est_xy, episode.covariances, strict=True))[
            :: max(1, len(est_xy) // 12)
        ]:
            _ellipse(ax, xy, np.reshape(cov, (2, 2)))
        ax.set_title(f"{name} (seed {episode.spec['seed']}): {episode.outcome}")
        ax.legend(fontsize=8)
    try:
        return save_figure(fig, path)
    finally:
        plt.close(fig)


def _ellipse(ax, xy: np.ndarray, cov: np.ndarray, sigma: float = 2.0) -> None:
    values, vectors = np.linalg.eigh(cov)
    angle = np.linspace(0, 2 * np.pi, 40)
    circle = np.stack([np.cos(angle), np.sin(angle)])
    points = vectors @ (sigma * np.sqrt(np.maximum(values, 0))[:, None] * circle)
    ax.plot(xy[0] + points[0], xy[1] + points[1], color="tab:red", lw=0.6, alpha=0.6)


def error_curves(episodes: list[EpisodeResult], grid: np.ndarray):
    """Mean position and heading error of the episodes on a grid of distance driven."""
    position, heading = [], []
    for e in episodes:
        inside = grid <= e.travelled[-1]
        position.append(np.where(inside, np.interp(grid, e.travelled, e.errors), np.nan))
        h = np.degrees(np.abs(e.heading_errors))
        heading.append(np.where(inside, np.interp(grid, e.travelled, h), np.nan))
    return _mean_over_episodes(position), _mean_over_episodes(heading)


def _mean_over_episodes(curves: list[np.ndarray]) -> np.ndarray:
    """Mean of the curves where at least one episode got that far (NaN elsewhere)."""
    stacked = np.array(curves)
    count = np.sum(~np.isnan(stacked), axis=0)
    total = np.nansum(stacked, axis=0)
    return np.where(count > 0, total / np.maximum(count, 1), np.nan)


def plot_errors(by_estimator: dict, path: Path) -> Path:
    """Position and orientation error vs distance driven, mean over episodes (Fig. 11 style)."""
    plt = _pyplot()
    longest = max(e.travelled[-1] for episodes in by_estimator.values() for e in episodes)
    grid = np.linspace(0, longest, 200)
    fig, (ax_p, ax_h) = plt.subplots(1, 2, figsize=(12, 4))
    for name, episodes in by_estimator.items():
        position, heading = error_curves(episodes, grid)
        ax_p.plot(grid, position, label=name)
        ax_h.plot(grid, heading, label=name)
    ax_p.set(xlabel="distance driven (m)", ylabel="position error (m)", title="(a) position")
    ax_h.set(
        xlabel="distance driven (m)", ylabel="orientation error (deg)", title="(b) orientation"
    )
    ax_p.legend()
    try:
        return save_figure(fig, path)
    finally:
        plt.close(fig)
