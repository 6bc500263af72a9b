"""The landmark density dial: measured coverage within its configured range, dark stretches
as long as configured; the suites load and register."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import stsf_gym  # noqa: F401 - registers the ids
from stsf_gym.envs.config import load_config
from stsf_gym.envs.suite import load_suite, suite_names
from stsf_gym.envs.worlds.coverage import landmark_coverage
from stsf_gym.envs.worlds.generator import generate_world
from stsf_gym.envs.worlds.generator_config import load_generator_config
from stsf_gym.validation import ConfigError

ENV = load_config()
SPARSE = {
    "min_path_length": 25.0,
    "segments": [3, 5],
    "segment_length": [4.0, 9.0],
    "visibility": {"coverage": [0.3, 0.6], "dark_stretch": [10.0, 20.0]},
}


@pytest.mark.slow
def test_measured_coverage_lies_in_the_configured_range_over_100_worlds():
    gen = load_generator_config(SPARSE)
    measured = [
        landmark_coverage(generate_world(seed, gen, ENV), gen, ENV)
        for seed in range(1_000_000, 1_000_100)
    ]
    fractions = np.array([m.fraction for m in measured])
    assert np.all((fractions >= 0.3) & (fractions <= 0.6)), fractions
    # a planned dark stretch is at least 10 m (less one sample step at each end)
    assert min(m.longest_dark_m for m in measured) >= 10.0 - 2 * gen.visibility.sample_step
    assert fractions.std() > 0.03  # the dial draws coverage across its range


@pytest.mark.slow
def test_the_default_density_sees_a_board_from_every_path_point():
    gen = load_generator_config()
    for seed in range(1_000_000, 1_000_020):
        coverage = landmark_coverage(generate_world(seed, gen, ENV), gen, ENV)
        assert coverage.fraction == 1.0 and coverage.longest_dark_m == 0.0


def test_bad_dial_values_are_named():
    with pytest.raises(ConfigError, match=r"coverage"):
        load_generator_config(visibility={**SPARSE["visibility"], "coverage": [0.6, 0.3]})
    with pytest.raises(ConfigError, match=r"coverage"):
        load_generator_config(visibility={**SPARSE["visibility"], "coverage": [0.0, 0.5]})


def test_suites_load_and_every_level_and_pose_source_is_registered():
    assert suite_names() == ["corridor", "junctions", "sparse"]
    for name in suite_names():
        suite = load_suite(name)
        assert load_config(suite.env).task.protocol == "declare"
        assert load_config(suite.env).camera.mode == "fast"
        for estimator in ("Odometry", "Conventional", "ConventionalFilter", "STSF", "EKF"):
            assert f"stsf_gym/Suite-{name.title()}-{estimator}-v0" in gym.registry
    with pytest.raises(ConfigError, match="unknown suite 'hardest'"):
        load_suite("hardest")


def test_sparse_suite_worlds_have_routes_halls_and_junctions():
    suite = load_suite("sparse")
    gen = suite.generator_config()
    env = load_config(suite.env)
    for seed in range(1_000_000, 1_000_005):
        world = generate_world(seed, gen, env)
        assert 2 <= len(world.goals) <= 3
        xs, ys = np.asarray(world.walls)[:, [0, 2]], np.asarray(world.walls)[:, [1, 3]]
        assert max(np.ptp(xs), np.ptp(ys)) >= gen.hall_width[0]  # the hall's span
        goal = np.asarray(world.goals[-1])
        ends = np.asarray(world.walls)
        # the goal stands in the open: no wall within the sonar's range
        gaps = [_segment_distance(goal, w) for w in ends]
        assert min(gaps) > env.sonar.max_range


def _segment_distance(point, wall) -> float:
    a, b = np.asarray(wall[:2]), np.asarray(wall[2:])
    t = np.clip(np.dot(point - a, b - a) / np.dot(b - a, b - a), 0, 1)
    return float(np.linalg.norm(point - a - t * (b - a)))


@pytest.mark.parametrize(
    "env_id", ["stsf_gym/Suite-Corridor-v0", "stsf_gym/Suite-Corridor-Odometry-v0"]
)
def test_a_section_given_to_a_suite_id_keeps_the_suites_other_keys(env_id):
    """``sonar={"cast": ...}`` changes the cast and keeps the suite's beam model and camera."""
    env = gym.make(env_id, sonar={"cast": "bullet"}, camera__width=160)
    try:
        config = env.unwrapped.config
        assert config.sonar.cast == "bullet" and config.sonar.beam.enabled
        assert config.camera.width == 160 and config.camera.mode == "fast"
        assert config.task.protocol == "declare"
    finally:
        env.close()
