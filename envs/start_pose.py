"""The episode's start pose: the world's ``start``, or one drawn near the path's beginning.

With ``task.start_along``, ``task.start_lateral`` and ``task.start_yaw_deg`` all 0 the robot
starts at the world's ``start`` (the paper's protocol: every reproduction). Otherwise the start
is drawn from the episode's ``start`` stream (:class:`~stsf_gym.envs.random_streams.RandomStreams`):

- an arc length ``s ~ U[0, start_along]`` along the path,
- an offset ``d ~ U[-start_lateral, start_lateral]`` along the path's left normal at ``s``,
- a heading ``psi(s) + U[-start_yaw_deg, start_yaw_deg]``, ``psi(s)`` the path's direction.

Training legs (``task.leg_max`` above 0, :func:`draw_leg`) draw the start anywhere on the
route, with one goal a few metres ahead. A drawn start models a robot set down by hand near
its dock, so a learned agent meets many start poses, not one it could memorise. The
estimators start from the drawn pose, as from an operator's initial pose (known start). A draw
closer than a body radius to a wall or an obstacle is drawn
again, as is one beyond a wall (the line from its path point crosses one), at most
:data:`MAX_DRAWS` times.
"""

from __future__ import annotations

import math

import numpy as np

from stsf_gym.envs.config import TaskConfig, WorldConfig
from stsf_gym.envs.task import Polyline
from stsf_gym.envs.worlds.spec import check_start_pose
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
    _check_lateral(world, path, (0.0, task.start_along), task, body_radius)
    return _draw_near(world, path, (0.0, task.start_along), task, body_radius, rng)


def legs(task: TaskConfig) -> bool:
    """Whether ``task`` drives training legs (``task.leg_max`` above 0)."""
    return task.leg_max > 0


def draw_leg(
    world: WorldConfig, task: TaskConfig, body_radius: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """A training leg of ``world``'s route: ``(start pose, goal)``.

    The goal's arc length is drawn uniformly over the route (from ``task.leg_min`` to the last
    goal's), the leg's length ``U[leg_min, leg_max]`` (cut at the route's start), and the start
    that far behind the goal, with the lateral and heading spread of ``task.start_*``. A leg
    therefore ends anywhere a route may stop, turns included, and a short episode still teaches
    the whole task: drive the corridor, then declare at the goal.
    """
    path = Polyline(world.path)
    end = path.project(np.asarray(world.goals[-1], dtype=float))
    require(
        task.leg_min < end,
        "task.leg_min",
        f"this world's route is {end:.2f} m long, shorter than a leg ({task.leg_min:g} m)",
    )
    _check_lateral(world, path, (0.0,), task, body_radius)
    for _ in range(MAX_DRAWS):
        goal_arc = rng.uniform(task.leg_min, end)
        start_arc = max(goal_arc - rng.uniform(task.leg_min, task.leg_max), 0.0)
        start = _draw_pose(world, path, start_arc, task, body_radius, rng)
        if start is not None:
            return start, path.point_at(goal_arc)
    raise FieldError(
        "task.start_lateral",
        f"no leg start a body radius ({body_radius:g} m) clear of walls and obstacles in "
        f"{MAX_DRAWS} draws within +-{task.start_lateral:g} m of the path: make it smaller",
    )


def _check_lateral(
    world: WorldConfig,
    path: Polyline,
    arcs: tuple[float, ...],
    task: TaskConfig,
    body_radius: float,
) -> None:
    """The lateral range's corners at ``arcs`` must be free floor (else the setting is bad)."""
    for s in arcs:
        for offset in (-task.start_lateral, task.start_lateral):
            require(
                _free(world, path, s, offset, body_radius),
                "task.start_lateral",
                f"{task.start_lateral:g} m across the path at {s:g} m along it puts the robot "
                f"into or beyond a wall (a body radius is {body_radius:g} m): make it smaller",
            )


def _draw_near(
    world: WorldConfig,
    path: Polyline,
    arcs: tuple[float, float],
    task: TaskConfig,
    body_radius: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """A pose at an arc length ``U[arcs]``, offset and turned as ``task.start_*`` allow."""
    for _ in range(MAX_DRAWS):
        pose = _draw_pose(world, path, rng.uniform(*arcs), task, body_radius, rng)
        if pose is not None:
            return pose
    raise FieldError(
        "task.start_lateral",
        f"no start pose a body radius ({body_radius:g} m) clear of walls and obstacles in "
        f"{MAX_DRAWS} draws within +-{task.start_lateral:g} m of the path: make it smaller",
    )


def _draw_pose(
    world: WorldConfig,
    path: Polyline,
    s: float,
    task: TaskConfig,
    body_radius: float,
    rng: np.random.Generator,
) -> np.ndarray | None:
    """A pose at arc length ``s``, offset and turned as ``task.start_*`` allow; None where the
    robot does not fit (a box or a turn's wall is there)."""
    offset = rng.uniform(-task.start_lateral, task.start_lateral)
    turn = math.radians(rng.uniform(-task.start_yaw_deg, task.start_yaw_deg))
    if not _free(world, path, s, offset, body_radius):
        return None
    x, y = _place(path, s, offset)
    return np.array([x, y, math.remainder(path.heading_at(s) + turn, math.tau)])


def _place(path: Polyline, s: float, offset: float) -> np.ndarray:
    """The point ``offset`` metres left of the path at arc length ``s``."""
    heading = path.heading_at(s)
    return path.point_at(s) + offset * np.array([-math.sin(heading), math.cos(heading)])


def _free(world: WorldConfig, path: Polyline, s: float, offset: float, body_radius: float) -> bool:
    """Whether the robot fits there: a body radius clear of walls and obstacles, on the path's
    side of every wall."""
    x, y = _place(path, s, offset)
    if _crosses_a_wall(world, path.point_at(s), (x, y)):
        return False
    try:
        check_start_pose(world, [x, y, 0.0], body_radius, "task.start_lateral")
    except FieldError:
        return False
    return True


def _crosses_a_wall(world: WorldConfig, a, b) -> bool:
    """Whether the segment ``a``-``b`` crosses a wall's centre line (orientation tests)."""
    walls = np.asarray(world.walls, dtype=float).reshape(-1, 4)
    p, q = walls[:, :2], walls[:, 2:]
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)

    def side(o, u, v):  # sign of the cross product (u - o) x (v - o), vectorised over walls
        return np.sign(
            (u[..., 0] - o[..., 0]) * (v[..., 1] - o[..., 1])
            - (u[..., 1] - o[..., 1]) * (v[..., 0] - o[..., 0])
        )

    return bool(np.any((side(a, b, p) != side(a, b, q)) & (side(p, q, a) != side(p, q, b))))
