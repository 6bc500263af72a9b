"""The scripted path follower: pure pursuit with sonar avoidance, on the true pose and on STSF."""

import math

import gymnasium as gym
import numpy as np
import pytest

from stsf_gym.agents.follower import PathFollower, load_follower_config
from stsf_gym.agents.sonar_avoidance import SonarAvoidance
from stsf_gym.experiments.episodes import EpisodeSpec, run_episode
from stsf_gym.validation import ConfigError

BODY_RADIUS, MAX_RANGE, SONARS = 0.25, 5.0, 16


def drive_on_truth(world: str, seed: int = 0, **follower_overrides):
    """Run the follower on ``info["true_pose"]`` and the sonar to the episode's end."""
    env = gym.make("stsf_gym/Corridor-v0", world=world, camera__enabled=False)
    follower = PathFollower.for_env(env, **follower_overrides)
    obs, info = env.reset(seed=seed)
    terminated = truncated = False
    while not (terminated or truncated):
        obs, _, terminated, truncated, info = env.step(
            follower.act(info["true_pose"], obs["sonar"])
        )
    env.close()
    return terminated, info


@pytest.mark.parametrize("world", ["irl_corridor", "irl_corridor_cluttered"])
def test_reaches_the_goal_on_the_true_pose(world):
    terminated, info = drive_on_truth(world, seed=1)
    assert terminated and not info["collision"]
    assert info["progress"] > 23.0  # the goal ends the 24 m path, within its 0.4 m radius


def test_without_avoidance_the_clutter_stops_it():
    terminated, info = drive_on_truth("irl_corridor_cluttered", seed=1, avoidance__enabled=False)
    assert terminated and info["collision"]
    assert info["progress"] < 10.0  # stopped by the first obstacles, far from the goal


@pytest.mark.slow
def test_reaches_the_goal_on_stsf():
    spec = EpisodeSpec(world="irl_corridor", estimator="stsf", seed=0, env={"camera__mode": "fast"})
    result = run_episode(spec)
    assert result.outcome == "goal"
    assert result.landmark_updates > 0  # the estimate, not dead reckoning alone, drove it


@pytest.fixture
def avoidance():
    cfg = load_follower_config().avoidance
    return SonarAvoidance(cfg, SONARS, BODY_RADIUS, MAX_RANGE)


def readings(**ranges: float) -> np.ndarray:
    """Max-range sonar with ``t<i>=range`` for the transducers that see something."""
    sonar = np.full(SONARS, MAX_RANGE, np.float32)
    for name, value in ranges.items():
        sonar[int(name[1:])] = value
    return sonar


def test_clear_sonar_leaves_pure_pursuit_unchanged(avoidance):
    v, w = 0.122, 0.05
    assert avoidance.adjust(readings(), 0.1, v, w, 0.6) == (v, w)


@pytest.mark.parametrize("side", [1, -1])
def test_obstacle_ahead_to_one_side_slows_and_steers_away(avoidance, side):
    # transducer 1 (22.5 deg left) or 15 (22.5 deg right) sees something 0.4 m off the ring
    sonar = readings(**{f"t{1 if side > 0 else 15}": 0.4})
    v, w = avoidance.adjust(sonar, 0.0, 0.122, 0.0, 0.6)
    assert 0 < v < 0.122
    assert side * w < 0  # away from the obstacle's side


def test_obstacle_right_ahead_stops_and_turns(avoidance):
    v, w = avoidance.adjust(readings(t0=0.15), 0.0, 0.122, 0.0, 0.6)
    assert v == 0.0 and abs(w) > 0


def test_free_distance_accounts_for_the_robot_width(avoidance):
    lane = BODY_RADIUS + avoidance.cfg.margin
    # a point straight ahead at 1 m from the centre is reached after 1 - lane metres
    points = avoidance.obstacle_points(readings(t0=1.0 - BODY_RADIUS))
    assert 1.0 - lane < avoidance.cfg.horizon
    assert avoidance.free_distance(points, 0.0)[0] == pytest.approx(1.0 - lane)
    # beside the lane it blocks nothing: turned so that the point is lane + 1 cm off the axis
    offset = math.asin((lane + 0.01) / 1.0)
    assert avoidance.free_distance(points, offset)[0] == avoidance.cfg.horizon


def test_corridor_walls_do_not_trigger_avoidance(make_env):
    env = make_env(camera__enabled=False, sonar__dropout_prob=0.0)
    follower = PathFollower.for_env(env)
    for seed, y in enumerate([-0.15, 0.0, 0.15]):  # centred and off-centre in the first leg
        obs, info = env.reset(seed=seed, options={"start_pose": [5.0, y, 0.0]})
        pose = info["true_pose"]
        assert obs["sonar"][4] < 1.0 and obs["sonar"][12] < 1.0  # both walls are seen
        np.testing.assert_array_equal(follower.act(pose, obs["sonar"]), follower.act(pose))


def test_bad_sonar_and_bad_config_are_named(avoidance):
    with pytest.raises(ValueError, match="16 sonar ranges"):
        avoidance.adjust(np.ones(8), 0.0, 0.122, 0.0, 0.6)
    with pytest.raises(ConfigError, match=r"follower\.avoidance\.margn"):
        load_follower_config(avoidance__margn=0.1)
    with pytest.raises(ConfigError, match="stop_distance"):
        load_follower_config(avoidance__stop_distance=1.0)


def test_exploring_without_a_pose_drives_ahead_and_turns_from_a_wall(make_env):
    env = make_env()
    follower = PathFollower.for_env(env)
    v, w = follower.explore(readings())
    assert v == pytest.approx(0.122 / env.unwrapped.config.robot.max_speed) and w == 0.0
    v, w = follower.explore(readings(t0=0.15))  # a wall right ahead: stop and turn
    assert v == 0.0 and abs(w) > 0


@pytest.mark.parametrize("seed", range(20))
def test_free_reach_kernel_is_the_numpy_expressions(seed):
    """The avoidance's compiled reach gives, to the bit, the array expressions it replaced:
    lateral offsets, the lane test, the front arc's chord, np.where and the capped minimum."""
    from stsf_gym.agents.sonar_avoidance import _free_reach

    rng = np.random.default_rng(seed)
    points = rng.uniform(-2.0, 2.0, (int(rng.integers(0, 16)), 2))
    if len(points) > 2:
        points[0] = np.nan
    headings = rng.uniform(-np.pi, np.pi, 9)
    directions = np.column_stack([np.cos(headings), np.sin(headings)])
    half_width, horizon = 0.3, 1.5
    along = directions @ points.T
    lateral = np.abs(directions[:, 0:1] * points[:, 1] - directions[:, 1:2] * points[:, 0])
    in_lane = (along > 0) & (lateral < half_width)
    reach = along - np.sqrt(np.clip(half_width**2 - lateral**2, 0.0, None))
    reach = np.where(in_lane, np.maximum(reach, 0.0), horizon)
    expected = np.minimum(reach.min(axis=1, initial=horizon), horizon)
    got = _free_reach(along, directions, points, half_width, half_width**2, horizon)
    assert got.tobytes() == expected.tobytes()
