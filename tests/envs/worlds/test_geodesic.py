"""SPL's geodesic route length (stsf_gym.envs.worlds.geodesic) on hand-built worlds whose
shortest path is known by hand geometry, and its way into the benchmark's SPL."""

from __future__ import annotations

import math

import numpy as np
import pytest

from stsf_gym.envs.config import WorldConfig, load_config
from stsf_gym.envs.generated_env import episode_config, world_seed_for
from stsf_gym.envs.suite import load_suite
from stsf_gym.envs.task import Polyline
from stsf_gym.envs.worlds.generator import generate_world
from stsf_gym.envs.worlds.geodesic import arc_error_bound, route_geodesic_length
from stsf_gym.experiments.benchmark.scores import episode_scores
from stsf_gym.experiments.jobs.cells import route_geodesic_m
from stsf_gym.validation import build

RADIUS = 0.25  # robot.body_radius in configs/default.yaml
THICKNESS = 0.1


def world(walls, path, obstacles=(), route=(), name="hand-built") -> WorldConfig:
    """A world of ``walls`` (centre lines) with no landmarks."""
    tree = {
        "name": name,
        "walls": [list(w) for w in walls],
        "wall_height": 2.0,
        "wall_thickness": THICKNESS,
        "path": [list(p) for p in path],
        "start": [*path[0], 0.0],
        "goal_radius": 0.4,
        "landmark_height": 0.9,
        "landmark_pattern": {"square_size": 0.05, "pitch": 0.1, "grid": 5, "border": 0.05},
        "landmarks": [],
        "obstacles": list(obstacles),
        "route": [list(g) for g in route],
    }
    return build(WorldConfig, tree, "world")


def straight(half_width=1.0, obstacles=(), extra_walls=()) -> WorldConfig:
    """A corridor along x from -1 to 11, ``half_width`` either side of y = 0."""
    w = half_width
    walls = [(-1, -w, 11, -w), (-1, w, 11, w), (-1, -w, -1, w), (11, -w, 11, w), *extra_walls]
    return world(walls, [(0, 0), (10, 0)], obstacles)


def l_corridor(route=()) -> WorldConfig:
    """The IRL corridor's L: east 14 m, a left turn, north 10 m; 1.6 m wide."""
    walls = [
        (-1.0, -0.8, 14.8, -0.8),
        (-1.0, 0.8, 13.2, 0.8),
        (-1.0, -0.8, -1.0, 0.8),
        (14.8, -0.8, 14.8, 11.0),
        (13.2, 0.8, 13.2, 11.0),
        (13.2, 11.0, 14.8, 11.0),
    ]
    return world(walls, [(0, 0), (14, 0), (14, 10)], route=route)


def around(a, centre, b, radius: float) -> tuple[float, float]:
    """The shortest path from ``a`` to ``b`` bent around the circle (``centre``, ``radius``)
    that blocks their straight line: (its length, the angle it turns). Two tangents and the
    arc between them: the arc spans the reflex angle at the centre between ``a`` and ``b``
    less, at each end, the angle between the end's ray and its tangent point's."""
    ca, cb = np.subtract(a, centre), np.subtract(b, centre)
    da, db = np.linalg.norm(ca), np.linalg.norm(cb)
    reflex = 2 * math.pi - math.acos(np.dot(ca, cb) / (da * db))
    arc = reflex - math.acos(radius / da) - math.acos(radius / db)
    return math.sqrt(da**2 - radius**2) + math.sqrt(db**2 - radius**2) + radius * arc, arc


def assert_within_bound(computed: float, exact: float, radius: float, turned: float) -> None:
    """The module's stated bound: ``exact - δ Θ <= computed <= exact``."""
    assert exact - arc_error_bound(radius) * turned - 1e-9 <= computed <= exact + 1e-9


def test_straight_corridor_is_the_straight_distance():
    corridor = straight()
    assert route_geodesic_length(corridor, (0, 0), RADIUS) == pytest.approx(10.0, abs=1e-9)
    off_centre = route_geodesic_length(corridor, (0.5, 0.3), RADIUS)
    assert off_centre == pytest.approx(math.hypot(9.5, 0.3))


def test_l_corridor_bends_around_the_inflated_inner_corner():
    # The inner corner's walls are boxes lengthened by half a thickness: the obstacle's convex
    # corner is (13.25, 0.75); grown by the robot's radius it is an arc of radius 0.25 there.
    exact, turned = around((0, 0), (13.2 + THICKNESS / 2, 0.8 - THICKNESS / 2), (14, 10), RADIUS)
    computed = route_geodesic_length(l_corridor(), (0, 0), RADIUS)
    assert_within_bound(computed, exact, RADIUS, turned)
    assert computed < 24.0 - 1.0  # the centre line, 24 m, is a metre longer


def test_obstacle_in_the_corridor_is_passed_on_its_tangents():
    cylinder = {"shape": "cylinder", "position": [5.0, 0.0], "size": [0.3, 1.0]}
    computed = route_geodesic_length(straight(2.0, [cylinder]), (0, 0), RADIUS)
    exact, turned = around((0, 0), (5, 0), (10, 0), 0.3 + RADIUS)
    assert_within_bound(computed, exact, 0.3 + RADIUS, turned)
    # a 1 m box turned 45 degrees: its top corner (5, 0.707) grown by the radius, passed above
    box = {"shape": "box", "position": [5.0, 0.0], "size": [1.0, 1.0, 1.0], "yaw_deg": 45.0}
    computed = route_geodesic_length(straight(2.0, [box]), (0, 0), RADIUS)
    exact, turned = around((0, 0), (5, math.sqrt(0.5)), (10, 0), RADIUS)
    assert_within_bound(computed, exact, RADIUS, turned)


def test_a_route_of_two_goals_sums_its_legs():
    # via the corner's centre-line point (14, 0): two straight legs, 14 m and 10 m, where the
    # route to the end alone cuts the corner
    via_corner = l_corridor(route=[(14, 0), (14, 10)])
    assert route_geodesic_length(via_corner, (0, 0), RADIUS) == pytest.approx(24.0)
    assert route_geodesic_length(l_corridor(), (0, 0), RADIUS) < 23.0


def test_a_start_inside_an_inflated_wall_starts_at_the_nearest_free_point():
    # 0.8 m off the centre line: clear of the wall (its face at 0.95 m), not of the robot's
    # radius; the free space ends at 1 - 0.05 - 0.25 = 0.7 m
    length = route_geodesic_length(straight(), (0, 0.8), RADIUS)
    assert length == pytest.approx(math.hypot(10, 0.7), abs=1e-6)


def test_no_path_names_the_world():
    walled_off = straight(extra_walls=[(5, -1, 5, 1)])
    with pytest.raises(ValueError, match="world 'hand-built': no collision-free path"):
        route_geodesic_length(walled_off, (0, 0), RADIUS)


def test_spl_is_below_one_for_a_longer_drive_and_one_on_the_geodesic():
    geodesic = route_geodesic_length(l_corridor(), (0, 0), RADIUS)
    stop = {"true_distance_m": 0.1, "success": True}

    def scored(distance: float) -> float:
        navigation = {
            "goals": 1,
            "route_length_m": 24.0,  # the centre line: SPL 1 for both drives if it were l
            "geodesic_length_m": geodesic,
            "stops": [stop],
        }
        result = {"outcome": "goal", "distance": distance, "navigation": navigation}
        return episode_scores({**result, "metrics": {"ate_rmse_m": 0.0}})["spl"]

    assert scored(24.0) == pytest.approx(geodesic / 24.0) and scored(24.0) < 0.96
    assert scored(geodesic) == 1.0


def test_a_benchmark_cell_measures_its_suite_world_from_the_true_start():
    suite = load_suite("corridor")
    gen = suite.generator_config()
    cell = {"world": "generated:test", "seed": 3, "env": suite.episode_env}
    drawn = generate_world(world_seed_for(gen.split_range("test"), 3), gen, load_config(suite.env))
    cfg = episode_config(cell["world"], cell["seed"], cell["env"])
    assert cfg.world == drawn  # the suite's generator, not the default one
    start = np.add(cfg.world.start[:2], (0.0, 0.1))
    length = route_geodesic_m(cell, start)
    assert length == pytest.approx(route_geodesic_length(cfg.world, start, RADIUS))
    assert length < Polyline(cfg.world.path).project(cfg.world.goals[-1])
