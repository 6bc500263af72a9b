"""The demonstrations' teacher on the student's own estimate (``teacher_pose: estimate``): its
label is the follower's action for the observation's pose, not the truth's."""

from __future__ import annotations

import numpy as np
import pytest

from stsf_gym.agents.demonstrations.expert import ExpertLabel
from stsf_gym.agents.follower import PathFollower
from stsf_gym.episode_env import make_episode_env

ENV = {"camera": {"enabled": False}, "task": {"protocol": "declare", "stop_action": True}}


def labels_along(pose: str, steps: int = 60) -> list[tuple[np.ndarray, np.ndarray, dict]]:
    env = ExpertLabel(make_episode_env("irl_corridor", "odometry", ENV), pose=pose)
    try:
        obs, info = env.reset(seed=0)
        seen = [(obs, info["expert_action"], info)]
        for _ in range(steps):
            obs, *_, info = env.step(np.array([0.5, 0.3, -1.0], np.float32))  # a drifting curve
            seen.append((obs, info["expert_action"], info))
        return seen
    finally:
        env.close()


def test_the_estimate_teacher_labels_what_the_follower_does_on_the_estimate():
    on_estimate, on_truth = labels_along("estimate"), labels_along("truth")
    env = make_episode_env("irl_corridor", "odometry", ENV)
    try:
        env.reset(seed=0)
        follower = PathFollower.for_env(env)
        for obs, label, _ in on_estimate:
            follower.head_for(float(obs["goal_arc"][0]))
            assert np.array_equal(label, follower.act(obs["pose"], obs["sonar"]))
    finally:
        env.close()
    differ = [not np.array_equal(a[1], b[1]) for a, b in zip(on_estimate, on_truth, strict=True)]
    assert any(differ)  # the odometry's estimate is off the truth: the labels tell them apart


def test_an_unknown_teacher_pose_is_refused():
    env = make_episode_env("irl_corridor", "odometry", ENV)
    try:
        with pytest.raises(ValueError, match="teacher"):
            ExpertLabel(env, pose="oracle")
    finally:
        env.close()
