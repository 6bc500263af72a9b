"""The task's public map knowledge in the observation (``goal``, ``goal_arc``, ``goals_left``,
``goal_count``), and the policy's input and the DAgger expert's goal read from it alone, never
from ``env.unwrapped.task``."""

import gymnasium as gym
import numpy as np
import pytest

import stsf_gym  # noqa: F401 - registers the ids
from stsf_gym.agents.demonstrations.expert import ExpertLabel
from stsf_gym.agents.observation import PolicyObservation
from stsf_gym.agents.registry import make_agent
from stsf_gym.envs.task import Polyline

TWO_GOALS = ("stsf_gym/Suite-Sparse-Truth-v0", 1)  # (id, seed): a generated route of two goals


def two_goal_episode():
    """The follower drives a two-goal route to its end: the env and each step's observation."""
    env_id, seed = TWO_GOALS
    env = gym.make(env_id, camera={"enabled": False})
    follower = make_agent("follower")
    obs, _ = env.reset(seed=seed)
    follower.begin(env)
    steps = [(obs, env.unwrapped.task.goal_index)]
    terminated = truncated = False
    while not (terminated or truncated):
        obs, _, terminated, truncated, info = env.step(follower.act(obs))
        steps.append((obs, env.unwrapped.task.goal_index))
    assert info["success"], "the follower should finish the route on the true pose"
    return env, steps


@pytest.fixture(scope="module")
def episode():
    env, steps = two_goal_episode()
    yield env, steps
    env.close()


def test_the_keys_hold_the_tasks_goal_arc_and_count_through_the_episode(episode):
    env, steps = episode
    task, space = env.unwrapped.task, env.observation_space
    assert len(task.goals) == 2
    for obs, index in steps:
        assert space.contains(obs)
        current = min(index, len(task.goals) - 1)
        np.testing.assert_array_equal(obs["goal"], task.goals[current])
        assert obs["goal_arc"][0] == task.goal_arcs[current]
        assert obs["goals_left"][0] == len(task.goals) - index
        assert obs["goal_count"][0] == 2
    lefts = [int(obs["goals_left"][0]) for obs, _ in steps]
    assert lefts[0] == 2 and lefts[-1] == 0 and 1 in lefts
    assert lefts == sorted(lefts, reverse=True)
    first, last = steps[0][0], steps[-1][0]
    assert first["goal_arc"][0] < last["goal_arc"][0]  # the second goal lies further along


class NoTask(gym.Env):
    """An env with the real one's config and spaces but no task: a policy that reached into
    ``unwrapped.task`` would fail here."""

    def __init__(self, real: gym.Env, keys=None) -> None:
        self.config, self.dt = real.unwrapped.config, real.unwrapped.dt
        spaces = real.observation_space.spaces
        self.observation_space = gym.spaces.Dict({k: spaces[k] for k in keys or spaces})
        self.action_space = real.action_space


def test_the_policys_input_is_read_from_the_observation_alone(episode):
    env, steps = episode
    reaching = PolicyObservation(env)  # over the env that has a task
    blind = PolicyObservation(NoTask(env))
    assert not hasattr(blind.unwrapped, "task")
    for obs, _ in steps:
        assert blind.observation(obs).tobytes() == reaching.observation(obs).tobytes()
    obs = dict(steps[0][0])
    share = 2 * len(blind.config.lookahead) + 3  # the entry after the goal vector
    assert blind.observation(obs)[share] == 1.0  # both goals left
    obs["goals_left"] = np.array([1])
    assert blind.observation(obs)[share] == 0.5
    moved = dict(obs, goal=obs["goal"] + 1.0)
    assert not np.array_equal(blind.observation(moved), blind.observation(obs))


def test_an_observation_without_the_task_keys_is_refused(episode):
    env, _ = episode
    keys = [k for k in env.observation_space.spaces if k not in ("goal_arc", "goal_count")]
    with pytest.raises(ValueError, match=r"task's obs keys \['goal_arc', 'goal_count'\]"):
        PolicyObservation(NoTask(env, keys))


class GoalAtStart(gym.ObservationWrapper):
    """Says the current goal lies where the robot was put, whatever the task holds."""

    def observation(self, obs):
        env = self.env.unwrapped
        start = Polyline(env.config.world.path).project(env.start_pose)
        return dict(obs, goal_arc=np.array([start]))


def test_the_expert_heads_for_the_observations_goal(make_env):
    env = make_env("stsf_gym/Suite-Corridor-Truth-v0", camera__enabled=False)  # with STOP
    _, info = ExpertLabel(env).reset(seed=0)
    assert info["expert_action"][-1] == -1.0  # the route's goal lies far ahead: drive on
    _, info = ExpertLabel(GoalAtStart(env)).reset(seed=0)
    assert info["expert_action"][-1] == 1.0  # the observation's goal is here: declare


def test_the_follower_heads_for_the_observations_goal(make_env, monkeypatch):
    env = make_env("stsf_gym/Suite-Corridor-Truth-v0", camera__enabled=False)  # with STOP
    follower = make_agent("follower")
    for wrapped, declares in ((env, -1.0), (GoalAtStart(env), 1.0)):
        obs, _ = wrapped.reset(seed=0)
        with monkeypatch.context() as blind:  # built without reading the task
            blind.setattr(
                type(env.unwrapped), "task", property(lambda _: pytest.fail("task")), raising=False
            )
            follower.begin(wrapped)
        assert follower.act(obs)[-1] == declares  # the goal far ahead, or here: declare
