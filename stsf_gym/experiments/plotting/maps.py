"""Figures of the experiments (matplotlib PNG): the world map, trajectories, error curves."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from stsf_gym.experiments.episodes import EpisodeResult
from stsf_gym.experiments.statistics import error_curves
from stsf_gym.io import save_figure


def pyplot():
    """``matplotlib.pyplot`` on the non-interactive Agg backend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def draw_world_config(ax, world) -> None:
    """Walls, obstacles, path, goal and landmarks of a world config on a top-down axis."""
    for x1, y1, x2, y2 in world.walls:
        ax.plot([x1, x2], [y1, y2], color="0.3", lw=3, solid_capstyle="butt")
    for obstacle in world.obstacles:
        ax.scatter(*obstacle.position, marker="s", s=60, color="tab:brown")
    path = np.asarray(world.path)
    ax.plot(*path.T, color="0.6", ls=":", label="path")
    ax.scatter(*world.goal, marker="*", s=150, color="gold", zorder=5, label="goal")
    for landmark in world.landmarks:
        at = np.asarray(landmark.at)
        normal = np.array(
            [np.cos(np.radians(landmark.facing_deg)), np.sin(np.radians(landmark.facing_deg))]
        )
        ax.scatter(*at, marker="s", s=30, color="k", zorder=5)
        ax.annotate(str(landmark.id), at + 0.4 * normal, ha="center", va="center", fontsize=8)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


def plot_trajectories(world: str, by_estimator: dict[str, list[EpisodeResult]], path: Path):
    """True and estimated paths of the first episode per estimator, over the map."""
    from stsf_gym.envs.generated_env import episode_world

    plt = pyplot()
    n = len(by_estimator)
    fig, axes = plt.subplots(1, n, figsize=(5 * n, 4.5), squeeze=False)
    for ax, (name, episodes) in zip(axes[0], by_estimator.items(), strict=True):
        episode = episodes[0]
        draw_world_config(ax, episode_world(world, episode.spec["seed"], episode.spec["env"]))
        true_xy, est_xy = np.array(episode.true_xy), np.array(episode.estimate_xy)
        ax.plot(*true_xy.T, color="tab:green", label="true")
        ax.plot(*est_xy.T, color="tab:red", ls="--", label="estimate")
        covs = episode.cov_matrices[:, :2, :2]
        for xy, cov in list(zip(est_xy, covs, strict=True))[:: max(1, len(est_xy) // 12)]:
            _ellipse(ax, xy, cov)
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


def plot_errors(by_estimator: dict[str, list[EpisodeResult]], path: Path) -> Path:
    """Position and orientation error vs distance driven, mean over episodes (Fig. 11 style)."""
    plt = pyplot()
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
