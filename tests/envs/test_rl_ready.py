"""RL-ready ids: one per suite and pose source, each declaring its episodes' most decisions,
passing Gymnasium's and SB3's checkers, with an action layout as the user steps it, and a fresh
policy whose training legs do not end in a false stop at once."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3 import PPO

import stsf_gym
from stsf_gym.agents.rl.declaration import (
    DISCRETE_ACTIONS,
    GOES_ON_FALSE_STOP,
    WEAN_FALSE_STOPS,
    WEAN_LEGS,
    WEAN_SUCCESS,
    GradedFalseStop,
    WeanedFalseStop,
)
from stsf_gym.agents.rl.ready import episode_decisions, task_reward
from stsf_gym.envs.suite import suite_names

EARLY = 5  # decisions: a false stop this early is a fresh policy's, not a learnt one


def test_every_suite_and_pose_source_has_an_id_that_declares_its_most_decisions():
    for suite in suite_names():
        limit = episode_decisions(suite)
        for estimator in stsf_gym.ESTIMATOR_IDS.values():
            spec = gym.spec(stsf_gym.rl_id(suite, estimator))
            assert spec.max_episode_steps == limit


@pytest.mark.parametrize("env_id", ["stsf_gym/RL-Corridor-Truth-v0", "stsf_gym/RL-Sparse-STSF-v0"])
def test_an_rl_ready_id_passes_both_checkers(env_id):
    from gymnasium.utils.env_checker import check_env
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make(env_id, sim__max_episode_seconds=20.0)
    try:
        check_env(env, skip_render_check=True)
        sb3_check_env(env, warn=False)
    finally:
        env.close()


def test_the_action_layout_is_read_from_the_env_as_stepped():
    env = gym.make("stsf_gym/RL-Sparse-STSF-v0")
    try:
        layout = env.get_wrapper_attr("action_layout")
        assert layout.names == ("v", "w", "stop") and env.action_space.shape == (3,)
        assert env.observation_space.shape == (37,)  # the policy's flat input, no image
    finally:
        env.close()


def test_the_camera_is_off_where_the_pose_source_reads_none():
    for estimator, enabled in (("truth", False), ("odometry", False), ("stsf", True)):
        env = gym.make(stsf_gym.rl_id("corridor", estimator))
        assert env.unwrapped.config.camera.enabled is enabled
        env.close()


def _early_false_stops(env: gym.Env, model: PPO, legs: int) -> int:
    """Legs (of ``legs``) that a fresh stochastic policy ends in a false stop within their
    first :data:`EARLY` decisions."""
    ended = 0
    for leg in range(legs):
        obs, _ = env.reset(seed=leg)
        for _ in range(EARLY):
            action, _ = model.predict(obs, deterministic=False)
            obs, _, terminated, truncated, info = env.step(action)
            if terminated or truncated:
                ended += int(bool(info["stops"]) and not info["collision"])
                break
    return ended


@pytest.mark.slow
def test_a_fresh_policy_does_not_end_most_legs_in_a_false_stop():
    """Measured over 50 legs: under the default declaration a false stop costs and the leg goes
    on; under the evaluation's rule (``declaration="stop"``) the same fresh policy ends most."""
    env = gym.make("stsf_gym/RL-Corridor-Truth-v0")
    model = PPO("MlpPolicy", env, seed=0, device="cpu")
    try:
        assert _early_false_stops(env, model, 50) < 25
    finally:
        env.close()
    strict = gym.make("stsf_gym/RL-Corridor-Truth-v0", declaration="stop")
    try:
        assert _early_false_stops(strict, model, 50) >= 25
    finally:
        strict.close()


def test_a_false_stop_on_a_training_leg_costs_and_the_leg_goes_on():
    env = gym.make("stsf_gym/RL-Corridor-Truth-v0")
    try:
        env.reset(seed=3)
        _, reward, terminated, _, info = env.step(np.array([0.0, 0.0, 1.0], np.float32))
        assert info["stops"] == 1 and not info["last_stop"]["success"]
        assert not terminated and reward == pytest.approx(GOES_ON_FALSE_STOP, abs=0.05)
    finally:
        env.close()
    val = gym.make("stsf_gym/RL-Corridor-Truth-v0", split="val")
    try:
        val.reset(seed=3)  # a full route: the task as evaluated
        _, _, terminated, _, info = val.step(np.array([0.0, 0.0, 1.0], np.float32))
        assert terminated and not info["success"]
    finally:
        val.close()


class _Stops(gym.Env):
    """Stops at the given true distances, one a step, each costing the flat goes-on cost."""

    observation_space = gym.spaces.Box(-1, 1, (1,))
    action_space = gym.spaces.Box(-1, 1, (1,))

    def __init__(self, distances: list[float], radius: float = 0.25) -> None:
        self.distances, self.radius, self.count = distances, radius, 0

    def reset(self, *, seed=None, options=None):
        self.count = 0
        return np.zeros(1, np.float32), {"stops": 0, "last_stop": {"success": False}}

    def step(self, action):
        d = self.distances[self.count]
        self.count += 1
        success = d <= self.radius
        reward = 10.0 if success else GOES_ON_FALSE_STOP
        last = {"success": success, "true_distance_m": d}
        return (
            np.zeros(1, np.float32),
            reward,
            success,
            False,
            {"stops": self.count, "last_stop": last, "success": success},
        )


def test_a_graded_false_stop_costs_the_progress_of_its_distance_and_never_pays():
    env = GradedFalseStop(_Stops([3.0, 0.6, 0.3, 0.2]), progress=1.0)
    env.reset()
    rewards = [env.step(np.zeros(1))[1] for _ in range(4)]
    assert rewards[:3] == pytest.approx([-1.0, -0.6, -0.3])  # capped at the flat cost
    assert all(r < 0 for r in rewards[:3]) and rewards[3] == 10.0  # the correct stop pays
    with pytest.raises(ValueError, match=r"reward\.progress"):
        GradedFalseStop(_Stops([]), progress=0.0)


def test_graded_declaration_on_the_id_grades_training_legs_only():
    env = gym.make("stsf_gym/RL-Corridor-Truth-v0", declaration="stop-graded")
    try:
        env.reset(seed=3)  # a leg's goal is 2-10 m ahead: a stop at once costs the flat cost
        _, reward, terminated, _, info = env.step(np.array([0.0, 0.0, 1.0], np.float32))
        assert info["last_stop"]["true_distance_m"] >= 1.0 and not terminated
        assert reward == pytest.approx(GOES_ON_FALSE_STOP, abs=0.05)
        assert any(isinstance(w, GradedFalseStop) for w in _wrappers(env))
    finally:
        env.close()
    val = gym.make("stsf_gym/RL-Corridor-Truth-v0", split="val", declaration="stop-graded")
    try:
        assert not any(isinstance(w, GradedFalseStop) for w in _wrappers(val))
    finally:
        val.close()


def _legs(env: WeanedFalseStop, legs: int) -> list[tuple[float, bool]]:
    """``legs`` legs of a false stop, then the goal: each step's reward and ending."""
    steps = []
    for _ in range(legs):
        env.reset()
        while True:
            _, reward, terminated, _, _ = env.step(np.zeros(1))
            steps.append((reward, terminated))
            if terminated:
                break
    return steps


class _Legs(_Stops):
    """One-step legs: each ends at its first step, on the goal or by the time limit."""

    def __init__(self, outcomes: list[bool]) -> None:
        super().__init__([])
        self.outcomes = outcomes

    def step(self, action):
        success = self.outcomes.pop(0)
        info = {"stops": int(success), "last_stop": {"success": success}, "success": success}
        return np.zeros(1, np.float32), 10.0 * success, success, not success, info


def _weaned_after(outcomes: list[bool]) -> bool:
    env = WeanedFalseStop(_Legs(list(outcomes)), cheap=-1.0, task_false_stop=-10.0)
    for _ in outcomes:
        env.reset()
        env.step(np.zeros(1))
    return env.weaned


def test_a_weaned_false_stop_ends_the_leg_at_the_tasks_cost_once_legs_succeed():
    env = WeanedFalseStop(_Stops([1.0, 0.1]), cheap=GOES_ON_FALSE_STOP, task_false_stop=-10.0)
    _, info = env.reset()
    assert info["weaned"] is False
    early = _legs(env, WEAN_LEGS)  # every leg: a false stop that goes on, then the goal
    assert early[:2] == [(GOES_ON_FALSE_STOP, False), (10.0, True)]
    assert len(early) == 2 * WEAN_LEGS and env.weaned  # 50 of 50 legs succeeded
    assert _legs(env, 1) == [(-10.0, True)]  # the task's rule: the false stop ends the leg
    assert _weaned_after([True] * (WEAN_LEGS - 1)) is False  # too few legs to judge
    short = int(WEAN_SUCCESS * WEAN_LEGS) - 1
    assert _weaned_after([True] * short + [False] * (WEAN_LEGS - short)) is False
    assert _weaned_after([False] * 10 + [True] * WEAN_LEGS) is True  # the last 50 count
    with pytest.raises(ValueError, match="task_false_stop"):
        WeanedFalseStop(_Stops([]), cheap=-1.0, task_false_stop=-0.5)


def _weaned_rare_after(false_stop_legs: int) -> bool:
    """Whether the rare-false-stop rule weans after 50 successful legs, the first
    ``false_stop_legs`` of them declaring one false stop on the way."""
    env = WeanedFalseStop(
        _Stops([1.0, 0.1]), cheap=-1.0, task_false_stop=-10.0, max_false_stops=WEAN_FALSE_STOPS
    )
    _legs(env, false_stop_legs)
    env.env.distances = [0.1]  # type: ignore[attr-defined]  # straight to the goal
    _legs(env, WEAN_LEGS - false_stop_legs)
    return env.weaned


def test_the_rare_rule_weans_only_once_false_stops_are_rare_as_well():
    assert WEAN_FALSE_STOPS == pytest.approx(-np.log(WEAN_SUCCESS))
    # every leg succeeds: the success rule alone weans, the rare rule waits for the false stops
    assert _weaned_rare_after(WEAN_LEGS) is False
    allowed = int(WEAN_FALSE_STOPS * WEAN_LEGS)  # 11 of 50 legs with one false stop: 0.22
    assert _weaned_rare_after(allowed) is True
    assert _weaned_rare_after(allowed + 1) is False
    with pytest.raises(ValueError, match="max_false_stops"):
        WeanedFalseStop(_Stops([]), cheap=-1.0, task_false_stop=-10.0, max_false_stops=-1.0)
    rare = gym.make("stsf_gym/RL-Corridor-Truth-v0", declaration="stop-cheap-rare")
    try:
        weaning = [w for w in _wrappers(rare) if isinstance(w, WeanedFalseStop)]
        assert len(weaning) == 1 and weaning[0]._max_false_stops == WEAN_FALSE_STOPS
    finally:
        rare.close()


def test_the_weaned_design_weans_training_legs_only_toward_the_tasks_own_cost():
    env = gym.make("stsf_gym/RL-Corridor-Truth-v0", declaration="stop-cheap-first")
    val = gym.make("stsf_gym/RL-Corridor-Truth-v0", split="val", declaration="stop-cheap-first")
    try:
        weaning = [w for w in _wrappers(env) if isinstance(w, WeanedFalseStop)]
        assert len(weaning) == 1 and not any(isinstance(w, WeanedFalseStop) for w in _wrappers(val))
        assert weaning[0]._extra == pytest.approx(task_reward("corridor").false_stop + 0.1)
    finally:
        env.close()
        val.close()


def _wrappers(env: gym.Env) -> list[gym.Env]:
    found = []
    while isinstance(env, gym.Wrapper):
        found.append(env)
        env = env.env
    return found


def test_discrete_actions_drive_and_declare():
    env = gym.make("stsf_gym/RL-Corridor-Truth-v0", declaration="discrete")
    try:
        assert env.action_space == gym.spaces.Discrete(len(DISCRETE_ACTIONS))
        assert env.get_wrapper_attr("action_names")[0] == "stop"
        _, first = env.reset(seed=1)
        start = first["true_pose"]
        _, _, _, _, info = env.step(1)  # forward: 0.122 m/s for 0.5 s
        moved = np.hypot(*(info["true_pose"][:2] - start[:2]))
        assert 0.03 < moved < 0.09 and not info["stops"]
        _, _, _, _, info = env.step(0)
        assert info["stops"] == 1
    finally:
        env.close()
