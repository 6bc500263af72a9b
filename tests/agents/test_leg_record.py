"""The leg record: how an episode ended and how near its goal the robot came, judged at the
true position; a follower that declares its goal, and a robot that stops at once and waits."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from stsf_gym.agents.follower_agent import FollowerAgent
from stsf_gym.agents.rl.leg_record import LEG_KEYS, LegRecord
from stsf_gym.envs.suite import load_suite
from stsf_gym.episode_env import make_episode_env


def test_a_follower_that_declares_its_goal_is_recorded_at_the_goal():
    env = {**load_suite("corridor").episode_env,
           "task": {"protocol": "declare", "stop_action": True},
           "sim": {"max_episode_seconds": 200.0}}  # fmt: skip
    recorded = LegRecord(make_episode_env("generated:test", "truth", env))
    follower = FollowerAgent()
    try:
        obs, _ = recorded.reset(seed=4)
        follower.begin(recorded)
        info: dict = {}
        for _ in range(10_000):
            obs, _, terminated, truncated, info = recorded.step(follower.act(obs))
            if terminated or truncated:
                break
        radius = recorded.unwrapped.task.goal_radius
    finally:
        recorded.close()
    assert info["success"], "the follower on the true pose declares this corridor goal"
    assert info["outcome"] == "goal" and info["false_stops"] == 0
    assert info["closest_m"] <= radius and info["in_radius"] >= 1


def test_a_robot_that_declares_at_once_and_waits_ends_at_the_time_limit():
    env = gym.make("stsf_gym/RL-Corridor-Truth-v0", sim__max_episode_seconds=5.0)
    recorded = LegRecord(env)
    stand_and_declare = np.array([0.0, 0.0, 1.0], np.float32)
    try:
        _, first = recorded.reset(seed=0)
        start = recorded.unwrapped.task.distance_to_goal(first["true_pose"])
        for _ in range(100):
            _, _, terminated, truncated, info = recorded.step(stand_and_declare)
            if terminated or truncated:
                break
    finally:
        recorded.close()
    assert truncated and not terminated  # a false stop on a training leg goes on
    assert {key: info[key] for key in LEG_KEYS}.keys() == set(LEG_KEYS)
    assert info["outcome"] == "time limit" and info["false_stops"] >= 1
    assert info["in_radius"] == 0 and abs(info["closest_m"] - start) < 0.05
