"""agents/rl/near_goals.py: the residual learner decides only near the goals; the untrained
learner still drives the follower's episode step for step, and no reward is lost."""

from __future__ import annotations

import pytest
from stable_baselines3 import PPO

from stsf_gym.agents.follower_agent import FollowerAgent
from stsf_gym.agents.policy_stack import policy_stack
from stsf_gym.agents.rl.near_goals import LearnerNearGoals
from stsf_gym.agents.rl.residual import ResidualConfig, start_as_follower
from stsf_gym.envs.suite import load_suite
from stsf_gym.episode_env import make_episode_env

NEAR = ResidualConfig(acts_within=2.0)


def suite_env(seconds: float = 300.0) -> dict:  # the follower reaches the test goal: 123 s
    env = load_suite("corridor").episode_env
    return {**env, "task": {"protocol": "declare", "stop_action": True},
            "sim": {"max_episode_seconds": seconds}}  # fmt: skip


def test_the_stack_decides_near_goals_only_where_the_config_says():
    def top(config: ResidualConfig):
        return policy_stack(
            make_episode_env("generated:test", "truth", suite_env()), {}, 5, config.bounds
        )

    near, everywhere = top(NEAR), top(ResidualConfig())
    try:
        assert isinstance(near, LearnerNearGoals)
        assert not isinstance(everywhere, LearnerNearGoals)
    finally:
        near.close()
        everywhere.close()


@pytest.mark.parametrize("source", ["truth", "stsf"])
def test_an_untrained_learner_near_goals_drives_the_followers_episode(source: str):
    alone = make_episode_env("generated:test", source, suite_env())
    stack = policy_stack(
        make_episode_env("generated:test", source, suite_env()),
        {"boards": 4, "predicted_sonar": True},
        5,
        NEAR.bounds,
    )
    model = PPO("MlpPolicy", stack, seed=0, device="cpu")
    start_as_follower(model.policy, NEAR)
    follower = FollowerAgent()
    try:
        obs, _ = alone.reset(seed=4)
        follower.begin(alone)
        solo_return, solo_steps = 0.0, 0
        while True:
            obs, reward, terminated, truncated, solo = alone.step(follower.act(obs))
            solo_return, solo_steps = solo_return + float(reward), solo_steps + 1
            if terminated or truncated:
                break
        obs, info = stack.reset(seed=4)
        learner_return, decided, alone_decisions, near = 0.0, 0, info["follower_decisions"], []
        control_steps = info["control_steps"]
        while True:
            action, _ = model.predict(obs, deterministic=True)
            obs, reward, terminated, truncated, info = stack.step(action)
            learner_return += float(reward)
            decided += 1
            alone_decisions += info["follower_decisions"]
            control_steps += info["control_steps"]
            near.append(stack.get_wrapper_attr("near_goal"))
            if terminated or truncated:
                break
    finally:
        alone.close()
        stack.close()
    assert solo["success"] and info["success"] and solo["stops"] == info["stops"]
    assert info["true_pose"] == pytest.approx(solo["true_pose"])
    assert learner_return == pytest.approx(solo_return)  # the follower's rewards folded in
    assert 0 < decided < alone_decisions  # most of the route driven by the follower alone
    assert all(near[:-1])  # every decision handed back is within reach of the goal
    assert (decided + alone_decisions) * 5 >= solo_steps > (decided + alone_decisions - 1) * 5
    assert control_steps == solo_steps  # every control step driven is counted once
