"""Shared drawing: the world map under trajectories."""

from __future__ import annotations

import numpy as np


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
