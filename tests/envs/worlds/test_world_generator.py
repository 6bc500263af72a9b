"""The world generator's guarantees: valid, visible, passable, deterministic, round-trips."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

from stsf_gym.envs.config import load_config
from stsf_gym.envs.worlds.generator import generate_world, path_clearance, world_tree
from stsf_gym.envs.worlds.generator_config import load_generator_config
from stsf_gym.envs.worlds.layout import Rect, boundary_walls
from stsf_gym.envs.worlds.visibility import CameraView, path_samples, seen_matrix
from stsf_gym.experiments.generated_worlds import write_world_yaml
from stsf_gym.validation import ConfigError

ENV = load_config()
GEN = load_generator_config()
SEEDS = range(1_000_000, 1_000_050)  # 50 test-split worlds


@pytest.fixture(scope="module")
def worlds():
    return {seed: generate_world(seed, GEN, ENV) for seed in SEEDS}


def seen_from_path(world, obstacles: bool = True) -> np.ndarray:
    """(path samples x landmarks) seen matrix recomputed from the WorldConfig alone."""
    samples, headings = path_samples(np.asarray(world.path, float), GEN.visibility.sample_step)
    offset = world.wall_thickness / 2 + 0.02
    normals = np.array(
        [
            [math.cos(math.radians(lm.facing_deg)), math.sin(math.radians(lm.facing_deg))]
            for lm in world.landmarks
        ]
    )
    centres = np.array([lm.at for lm in world.landmarks]) + offset * normals
    circles = (
        [
            (*o.position, o.size[0] if o.shape == "cylinder" else math.hypot(*o.size[:2]) / 2)
            for o in world.obstacles
        ]
        if obstacles
        else []
    )
    return seen_matrix(
        samples,
        headings,
        centres,
        normals,
        np.asarray(world.walls, float),
        np.array(circles, float).reshape(-1, 3),
        world.wall_thickness,
        world.landmark_pattern.size,
        world.landmark_height,
        CameraView.from_env_config(ENV),
        GEN.visibility,
    )


@pytest.mark.slow
def test_worlds_pass_the_env_checks(worlds):
    for seed, world in worlds.items():
        cfg = load_config(world=world_tree(seed, GEN, ENV))  # world and clearance checks
        assert cfg.world == world
        length = np.sum(np.linalg.norm(np.diff(np.asarray(world.path), axis=0), axis=1))
        assert length >= GEN.min_path_length
        assert GEN.segments[0] <= len(world.path) - 1 <= GEN.segments[1]
        # every world starts at the origin and stays inside the pose space the wrapper gives
        # the first world (its bounds +-50 m)
        assert world.start == (0.0, 0.0, 0.0) and np.abs(world.walls).max() < 49.0


def test_a_landmark_is_seen_from_every_path_point(worlds):
    for seed, world in worlds.items():
        seen = seen_from_path(world)
        assert seen.any(axis=1).all(), f"world {seed}"
    # the check can fail: without the landmarks that cover the start, the start sees none
    world = worlds[SEEDS[0]]
    seen = seen_from_path(world)
    assert not np.delete(seen, np.flatnonzero(seen[0]), axis=1)[0].any()


def test_the_path_is_passable(worlds):
    body = ENV.robot.body_radius
    for seed, world in worlds.items():
        assert path_clearance(world) >= body + GEN.clutter.path_clearance - 1e-6, seed
    assert sum(len(w.obstacles) for w in worlds.values()) > 10  # clutter was placed


def test_worlds_vary_in_shape(worlds):
    turns = [len(w.path) - 2 for w in worlds.values()]
    assert set(turns) == set(range(GEN.segments[0] - 1, GEN.segments[1]))
    # dead-end branches: walls beyond what the main path's corridor needs
    assert len({len(w.walls) for w in worlds.values()}) > 5


def test_same_seed_same_world_different_seeds_differ():
    a, b = world_tree(7, GEN, ENV), world_tree(7, GEN, ENV)
    assert yaml.safe_dump(a) == yaml.safe_dump(b)  # bit-identical geometry
    trees = [yaml.safe_dump(world_tree(s, GEN, ENV)["walls"]) for s in range(20)]
    assert len(set(trees)) == 20


def test_yaml_round_trip(tmp_path):
    path = write_world_yaml(1_000_003, tmp_path / "world.yaml")
    assert load_config(world=path).world == generate_world(1_000_003, GEN, ENV)


def test_seen_matrix_limits():
    """One board on a wall at x = 0 facing +x, seen from points on the x axis."""
    samples = np.array([[0.5, 0.0], [4.0, 0.0], [12.0, 0.0], [4.0, 0.0]])
    headings = np.array([math.pi, math.pi, math.pi, 0.0])
    walls = np.array([[0.0, -2.0, 0.0, 2.0], [2.0, 1.0, 2.0, -1.0]])  # a screen at x = 2
    args = (np.array([[0.07, 0.0]]), np.array([[1.0, 0.0]]))
    view = CameraView.from_env_config(ENV)
    common = (0.1, 0.6, 0.9, view, GEN.visibility)
    open_room = seen_matrix(samples, headings, *args, walls[:1], np.zeros((0, 3)), *common)
    # too near (< min_range), in range, too far, in range but behind the robot (pan 180 deg)
    assert open_room[:, 0].tolist() == [False, True, False, False]
    screened = seen_matrix(samples, headings, *args, walls, np.zeros((0, 3)), *common)
    assert not screened.any()
    cluttered = seen_matrix(samples, headings, *args, walls[:1], np.array([[2, 0, 0.2]]), *common)
    assert not cluttered.any()


def test_boundary_walls_of_an_l():
    legs = [Rect(0, -1, 10, 1), Rect(8, -1, 10, 6)]
    walls = boundary_walls(legs, 0.1)
    assert len(walls) == 6
    lengths = sorted(round(math.dist(w[:2], w[2:]), 6) for w, _ in walls)
    assert lengths == [2.1, 2.1, 5.0, 7.1, 8.0, 10.1]  # wall centre lines, 5 cm out


def test_bad_generator_config_is_named():
    with pytest.raises(ConfigError, match=r"generator\.segments must be \[low, high\]"):
        load_generator_config(segments=[5, 2])
    with pytest.raises(ConfigError, match="must not overlap"):
        load_generator_config(splits={"train": [0, 10], "test": [5, 10]})
    with pytest.raises(ValueError, match="non-negative integer"):
        world_tree(-1, GEN, ENV)
