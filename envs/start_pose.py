"""The episode's start pose: the world's ``start``, or one drawn near the path's beginning.

With ``task.start_along``, ``task.start_lateral`` and ``task.start_yaw_deg`` all 0 the robot
starts at the world's ``start`` (the paper's protocol: every reproduction). Otherwise the start
is drawn from the episode's ``start`` stream (:class:`~stsf_gym.envs.random_streams.RandomStreams`):

- an arc length ``s ~ U[0, start_along]`` along the path,
- an offset ``d ~ U[-start_lateral, start_lateral]`` along the path's left normal at ``s``,
- a heading ``psi(s) + U[-start_yaw_deg, start_yaw_deg]``, ``psi(s)`` the path's direction.

It models a robot set down by hand near its dock, so a learned agent meets many start poses,
not one it could memorise. The estimators start from the drawn pose, as from an operator's
initial pose (known start). A draw closer than a body radius to a wall or an obstacle is drawn
again, at most :data:`MAX_DRAWS` times.
"""

from __future__ import annotations

import math

import numpy as np

from stsf_gym.envs.config import TaskConfig, WorldConfig
from stsf_gym.envs.task import Polyline
from stsf_gym.envs.worlds.checks import check_start_pose
from stsf_gym.validation import FieldError, require

MAX_DRAWS = 100


def start_spread(task: TaskConfig) -> bool:
    """Whether ``task`` draws the start (any ``start_*`` above 0)."""
    return any((task.start_along, task.start_lateral, task.start_yaw_deg))


def draw_start_pose(
    world: WorldConfig, task: TaskConfig, body_radius: float, rng: np.random.Generator
) -> np.ndarray:
    """The start pose ``[x, y, yaw]`` of an episode in ``world`` (see the module's docstring)."""
    if not start_spread(task):
        return np.asarray(world.start, dtype=float)
    path = Polyline(world.path)
    first_goal = world.goals[0] if task.protocol == "declare" else world.path[-1]
    room = path.project(np.asarray(first_goal, dtype=float)) - task.goal_radius
    require(
        task.start_along < room,
        "task.start_along",
        f"must leave the first goal ahead of every start: this world's first goal is "
        f"{room + task.goal_radius:.2f} m along its path, so at most {max(room, 0):.2f} m, "
        f"got {task.start_along:g}",
    )
    for _ in range(MAX_DRAWS):
        s = rng.uniform(0.0, task.start_along)
        offset = rng.uniform(-task.start_lateral, task.start_lateral)
        turn = math.radians(rng.uniform(-task.start_yaw_deg, task.start_yaw_deg))
        heading = path.heading_at(s)
        x, y = path.point_at(s) + offset * np.array([-math.sin(heading), math.cos(heading)])
        yaw = math.remainder(heading + turn, math.tau)
        try:
            return check_start_pose(world, [x, y, yaw], body_radius, "task.start_lateral")
        except FieldError:
            continue
    raise FieldError(
        "task.start_lateral",
        f"no start pose a body radius ({body_radius:g} m) clear of walls and obstacles in "
        f"{MAX_DRAWS} draws within +-{task.start_lateral:g} m of the path: make it smaller",
    )
