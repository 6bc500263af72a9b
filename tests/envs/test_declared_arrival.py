"""The declared-stop task (task.protocol: declare): the stop rule, a route's order, info."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import stsf_gym  # noqa: F401 - registers the ids
from stsf_gym.envs.config import load_config
from stsf_gym.envs.task import PathTask
from stsf_gym.validation import ConfigError

DT = 0.1


def task(route=None, **settings) -> PathTask:
    """The declare task on the straight 10 m corridor (goal at x = 10), or a route on it."""
    world = {**_straight(), "route": route} if route else "straight_10m"
    cfg = load_config(world=world, task={"protocol": "declare", **settings})
    return PathTask(cfg.world, cfg.reward, cfg.task)


def _straight() -> dict:
    from stsf_gym.config_files import CONFIG_DIR
    from stsf_gym.envs.config import read_yaml

    return read_yaml(CONFIG_DIR / "worlds" / "straight_10m.yaml")


def drive_then_stop(t: PathTask, xy, still_steps: int) -> list[bool]:
    """One moving step at ``xy``, then ``still_steps`` standing still there."""
    reached = [t.update(np.array(xy), 0.1, 0.0, DT, DT)]
    reached += [t.update(np.array(xy), 0.0, 0.0, DT, DT * (k + 2)) for k in range(still_steps)]
    return reached


@pytest.mark.parametrize(("offset", "success"), [(0.249, True), (0.251, False)])
def test_declared_stop_inside_the_radius_succeeds_outside_fails(offset, success):
    t = task()
    assert t.goal_radius == 0.25
    drive_then_stop(t, [10.0 - offset, 0.0], 10)  # 10 still steps = stop_seconds 1.0
    assert len(t.stops) == 1
    assert t.stops[0].true_distance_m == pytest.approx(offset)
    assert t.stops[0].success is success
    assert t.success is success and t.finished


def test_standing_still_shorter_than_stop_seconds_declares_nothing():
    t = task()
    drive_then_stop(t, [10.0, 0.0], 9)
    assert t.stops == [] and not t.finished
    # standing still at the start, before moving, is no declaration either
    t = task()
    for k in range(30):
        t.update(np.array([0.0, 0.0]), 0.0, 0.0, DT, DT * k)
    assert t.stops == []


def test_turning_on_the_spot_is_not_standing_still():
    t = task()
    t.update(np.array([10.0, 0.0]), 0.1, 0.0, DT, 0.0)
    for k in range(20):
        t.update(np.array([10.0, 0.0]), 0.0, 0.5, DT, DT * k)
    assert t.stops == []


def test_route_goals_are_visited_in_order():
    route = [[4.0, 0.0], [7.0, 0.0], [10.0, 0.0]]
    t = task(route)
    drive_then_stop(t, [7.0, 0.0], 10)  # the second goal first: the stop is 3 m off goal 0
    assert [s.goal for s in t.stops] == [0] and not t.stops[0].success and t.finished
    t = task(route)
    for goal in route:
        drive_then_stop(t, goal, 10)
    assert [(s.goal, s.success) for s in t.stops] == [(0, True), (1, True), (2, True)]
    assert t.success


def test_a_route_off_the_path_or_out_of_order_is_named():
    with pytest.raises(ConfigError, match=r"route\[0\].*on the path"):
        load_config(world={**_straight(), "route": [[4.0, 1.0], [10.0, 0.0]]})
    with pytest.raises(ConfigError, match=r"route\[1\].*further along"):
        load_config(world={**_straight(), "route": [[7.0, 0.0], [4.0, 0.0], [10.0, 0.0]]})
    with pytest.raises(ConfigError, match=r"route\[0\].*path's end"):
        load_config(world={**_straight(), "route": [[7.0, 0.0]]})


def test_driving_through_the_goal_without_stopping_is_no_success():
    env = gym.make(
        "stsf_gym/Straight10m-v0", camera__enabled=False, task__protocol="declare"
    ).unwrapped
    env.reset(seed=0)
    passed = False
    for _ in range(1000):
        _, _, terminated, truncated, info = env.step(np.array([1.0, 0.0]))
        if info["true_pose"][0] > 10.3:  # through the goal circle and out again
            passed = True
        if terminated or truncated:
            break
    env.close()
    assert passed and terminated and info["collision"]  # on to the end wall
    assert not info["success"] and info["stops"] == 0 and info["goals_reached"] == 0


def test_reach_protocol_ends_when_the_truth_enters_the_goal():
    env = gym.make("stsf_gym/Straight10m-v0", camera__enabled=False).unwrapped
    env.reset(seed=0)
    for _ in range(1000):
        _, _, terminated, truncated, info = env.step(np.array([1.0, 0.0]))
        if terminated or truncated:
            break
    env.close()
    assert terminated and info["success"] and not info["collision"]
    assert np.hypot(*(info["true_pose"][:2] - [10.0, 0.0])) <= 0.3  # the world's goal_radius


def test_the_follower_declares_arrival_on_the_true_pose():
    from stsf_gym.experiments.episodes import EpisodeSpec, run_episode

    env = {"camera": {"mode": "fast"}, "task": {"protocol": "declare"}}
    episode = run_episode(EpisodeSpec("straight_10m", "truth", 0, env=env))
    assert episode.outcome == "goal"
    assert len(episode.stops) == 1 and episode.stops[0]["true_distance_m"] < 0.1


def test_progress_stops_at_the_current_goal():
    """Driving past a goal earns no progress (so no reward for not stopping); after the goal
    is declared, progress runs on to the next one."""
    t = task([[4.0, 0.0], [10.0, 0.0]])
    assert t.progress(np.array([3.0, 0.0])) == pytest.approx(3.0)
    assert t.progress(np.array([6.0, 0.0])) == pytest.approx(4.0)  # past goal 0: held there
    drive_then_stop(t, [4.0, 0.0], 10)
    assert t.goal_index == 1
    assert t.progress(np.array([6.0, 0.0])) == pytest.approx(6.0)
    reach = PathTask(*_configs(load_config(world="straight_10m")))
    assert reach.progress(np.array([9.0, 0.0])) == pytest.approx(9.0)  # reach: the path's


def _configs(cfg):
    return cfg.world, cfg.reward, cfg.task
