"""The cautious follower's rule on hand-built observations: it slows near a goal and waits
there while its position estimate is unsure, declares once sure or once its wait is used up,
and drives wherever the follower does."""

import math

import numpy as np
import pytest

from stsf_gym.agents import cautious_follower as cf
from stsf_gym.agents.follower import load_follower_config
from stsf_gym.agents.registry import make_agent

PATH = [[0.0, 0.0], [10.0, 0.0]]
GOAL = 5.0  # m along the path
RADIUS, LIMIT, DT = 0.25, 600.0, 0.1
MAX_SPEED, MAX_YAW = 0.5, 1.0


def follower(stop_action: bool = True, hold_steps: int = 0) -> cf.CautiousFollower:
    f = cf.CautiousFollower(
        PATH, load_follower_config(), MAX_SPEED, MAX_YAW, None, True, hold_steps, stop_action
    )
    f.configure_caution(RADIUS, LIMIT, 0.1, DT)
    f.see_goal(GOAL, 1)  # the observation's one goal left
    return f


def cov(sigma: float) -> np.ndarray:
    return np.diag([sigma**2, sigma**2, 0.01])


def step(f: cf.CautiousFollower, x: float, sigma: float, time: float = 10.0) -> np.ndarray:
    f.observe(cov(sigma), time)
    return f.act(np.array([x, 0.0, 0.0]))


SURE = 0.5 * cf.SIGMA_SHARE * RADIUS
UNSURE = 2.0 * cf.SIGMA_SHARE * RADIUS


def test_sigma_is_the_long_axis_of_the_position_ellipse():
    rotated = np.array([[0.05, 0.03, 0.0], [0.03, 0.05, 0.0], [0.0, 0.0, 1.0]])
    assert cf.position_sigma(rotated) == pytest.approx(math.sqrt(0.08))
    assert cf.position_sigma(rotated.ravel()) == pytest.approx(math.sqrt(0.08))


def test_sure_at_the_goal_it_declares_at_once():
    assert step(follower(), GOAL, SURE)[2] == 1.0


def test_unsure_at_the_goal_it_stands_without_declaring_until_sure():
    f = follower()
    for _ in range(20):
        action = step(f, GOAL, UNSURE)
        assert action[2] == -1.0 and np.allclose(action[:2], 0.0)
    assert step(f, GOAL, SURE)[2] == 1.0


def test_its_wait_is_bounded_by_the_budget_and_by_half_the_time_left():
    f = follower()
    budget = round(cf.MAX_WAIT_S / DT)
    waits = [step(f, GOAL, UNSURE)[2] for _ in range(budget + 1)]
    assert waits[:budget] == [-1.0] * budget and waits[budget] == 1.0
    late = follower()
    waits = [step(late, GOAL, UNSURE, time=LIMIT - 10.0)[2] for _ in range(60)]
    assert waits.index(1.0) == round(5.0 / DT)  # half of the 10 s left


def test_without_a_stop_entry_it_waits_turning_on_the_spot():
    action = step(follower(stop_action=False, hold_steps=11), GOAL, UNSURE)
    assert action[0] == 0.0 and action[1] * MAX_YAW == pytest.approx(0.1)


def test_unsure_near_a_goal_it_creeps_and_far_from_it_drives_as_the_follower():
    near = GOAL - 0.8 * cf.APPROACH_M
    assert step(follower(), near, UNSURE)[0] * MAX_SPEED == pytest.approx(cf.CREEP_SPEED)
    assert step(follower(), near, SURE)[0] * MAX_SPEED > cf.CREEP_SPEED
    assert step(follower(), 1.0, UNSURE)[0] * MAX_SPEED == pytest.approx(0.122)


def test_it_is_an_agent_by_name_and_drives_an_env(make_env):
    agent = make_agent("cautious-follower")
    assert agent.label() == "cautious-follower"
    assert agent.config()["caution"]["sigma_share"] == cf.SIGMA_SHARE
    env = agent.wrap(
        make_env(
            "stsf_gym/Suite-Corridor-Odometry-v0", camera__enabled=False, sim__max_episode_seconds=3
        )
    )
    obs, _ = env.reset(seed=0)
    agent.begin(env)
    for _ in range(30):
        obs, _, terminated, truncated, _ = env.step(agent.act(obs))
        if terminated or truncated:
            break
    assert truncated
