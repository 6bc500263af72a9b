"""The learner's task: the STOP action, the action layout by name, training legs and the
decision interval (estimators on every control step; one policy stack for training and
evaluation)."""

from __future__ import annotations

import numpy as np
import pytest

from stsf_gym.agents.decision_interval import DecisionInterval
from stsf_gym.agents.registry import FollowerAgent, make_agent
from stsf_gym.agents.trained_agent import SB3Agent
from stsf_gym.envs.action_layout import ActionLayout
from stsf_gym.envs.config import load_config
from stsf_gym.envs.start_pose import draw_leg
from stsf_gym.envs.task import PathTask, Polyline
from stsf_gym.validation import ConfigError
from stsf_gym.wrappers import CameraPointingWrapper, PoseEstimateWrapper

STOP_TASK = {"protocol": "declare", "stop_action": True}
NO_CAMERA = {"camera__enabled": False}


def stop_task(**reward) -> PathTask:
    cfg = load_config(world="straight_10m", task=STOP_TASK, reward=reward or {})
    return PathTask(cfg.world, cfg.reward, cfg.task)


@pytest.mark.parametrize(("offset", "success"), [(0.249, True), (0.251, False)])
def test_stop_declares_at_once_inside_the_radius_only(offset, success):
    t = stop_task()
    assert t.update(np.array([10.0 - offset, 0.0]), 0.1, 0.3, 0.1, 0.1, stop=False) is False
    assert t.stops == []  # moving without STOP declares nothing; no stillness needed either
    assert t.update(np.array([10.0 - offset, 0.0]), 0.1, 0.3, 0.1, 0.2, stop=True) is success
    assert [s.success for s in t.stops] == [success] and t.finished


def test_standing_still_is_no_declaration_with_a_stop_action():
    t = stop_task()
    t.update(np.array([9.0, 0.0]), 0.1, 0.0, 0.1, 0.1)
    for k in range(30):
        t.update(np.array([10.0, 0.0]), 0.0, 0.0, 0.1, 0.2 + 0.1 * k)
    assert t.stops == [] and not t.finished


def test_a_stop_far_away_ends_the_episode_as_a_miss_and_costs_the_false_stop(make_env):
    env = make_env(
        "stsf_gym/Straight10m-v0", task=STOP_TASK, reward={"false_stop": -7.0}, **NO_CAMERA
    )
    assert env.unwrapped.action_layout.names == ("v", "w", "stop")
    env.reset(seed=0)
    _, reward, terminated, truncated, info = env.step(np.array([0.5, 0.0, 1.0], np.float32))
    assert terminated and not truncated and not info["success"]
    assert info["stops"] == 1 and info["last_stop"]["true_distance_m"] > 9.0
    assert reward == pytest.approx(-7.0, abs=0.05)  # the penalty, beside a step's progress


def test_stop_action_needs_the_declare_protocol():
    with pytest.raises(ConfigError, match=r"task\.protocol"):
        load_config(task={"protocol": "reach", "stop_action": True})


def test_the_layout_reads_entries_by_name():
    layout = ActionLayout.for_env("pan_tilt", True)
    assert layout.names == ("v", "w", "pan", "tilt", "stop")
    action = np.array([0.1, 0.2, 0.3, 0.4, 0.5], np.float32)
    assert layout.stops(action) and layout.mount(action).tolist() == pytest.approx([0.3, 0.4])
    agent = layout.without("pan")
    assert agent.names == ("v", "w", "tilt", "stop")
    full = layout.fill(np.array([1, 2, 4, 5], np.float32), agent, pan=3.0)
    assert full.tolist() == [1, 2, 3, 4, 5]
    with pytest.raises(ValueError, match="shape"):
        layout.fill(np.zeros(3), agent, pan=0.0)
    with pytest.raises(ValueError, match="must follow"):
        ActionLayout(("v", "w", "stop", "pan"))


def test_the_pan_wrapper_keeps_the_stop_entry_last(make_env):
    corridor = make_env(
        "stsf_gym/Straight10m-v0", camera__control="pan", task=STOP_TASK, **NO_CAMERA
    )
    env = CameraPointingWrapper(PoseEstimateWrapper(corridor, "odometry"))
    assert env.action_layout.names == ("v", "w", "stop") and env.action_space.shape == (3,)
    env.reset(seed=0)
    *_, terminated, _, info = env.step(np.array([0.0, 0.0, 1.0], np.float32))
    assert terminated and info["stops"] == 1  # the stop reached the env past the pan


LEG_TASK = {"protocol": "declare", "leg_min": 2.0, "leg_max": 5.0, "start_lateral": 0.1}


def test_legs_lie_on_the_route_and_repeat_with_the_seed():
    cfg = load_config(world="irl_corridor", task=LEG_TASK)
    path = Polyline(cfg.world.path)
    end = path.project(np.asarray(cfg.world.goals[-1]))
    draws = [
        draw_leg(cfg.world, cfg.task, cfg.robot.body_radius, np.random.default_rng(7))
        for _ in range(2)
    ]
    assert np.array_equal(draws[0][0], draws[1][0]) and np.array_equal(draws[0][1], draws[1][1])
    rng = np.random.default_rng(3)
    for _ in range(50):
        start, goal = draw_leg(cfg.world, cfg.task, cfg.robot.body_radius, rng)
        s, g = path.project(start), path.project(goal)
        assert 0 <= s < g <= end + 1e-9
        assert g - s <= 5.0 + 0.2 and (g - s >= 2.0 - 0.2 or s < 0.2)  # start's lateral jitter
        assert np.linalg.norm(path.point_at(g) - goal) < 1e-9  # the goal is on the path


def test_a_leg_env_visits_the_leg_goal_only(make_env):
    env = make_env("stsf_gym/Corridor-v0", task=LEG_TASK, **NO_CAMERA)
    env.reset(seed=4)
    task = env.unwrapped.task
    assert len(task.goals) == 1
    along = task.path.project(task.goals[0]) - task.path.project(env.unwrapped.start_pose)
    assert 2.0 - 0.2 <= along <= 5.0 + 0.2


def test_leg_settings_are_checked():
    with pytest.raises(ConfigError, match=r"task\.leg_min"):
        load_config(task={**LEG_TASK, "leg_min": 6.0})


def test_the_decision_interval_holds_the_action_and_the_estimator_sees_every_step(make_env):
    env = PoseEstimateWrapper(make_env("stsf_gym/Straight10m-v0", **NO_CAMERA), "odometry")
    updates = []
    update = env.estimator.update
    env.estimator.update = lambda obs, dt: (updates.append(dt), update(obs, dt))[1]
    held = DecisionInterval(env, 5)
    held.reset(seed=0)
    *_, info = held.step(np.array([1.0, 0.0], np.float32))
    assert info["control_steps"] == 5 and len(updates) == 5
    assert updates == pytest.approx([env.unwrapped.dt] * 5)
    assert info["sim_time"] == pytest.approx(5 * env.unwrapped.dt)
    with pytest.raises(ValueError, match="decision_steps"):
        DecisionInterval(env, 0)


def test_a_held_stop_declares_once(make_env):
    route = {"route": [[3.0, 0.0], [10.0, 0.0]]}
    from stsf_gym.config_files import CONFIG_DIR
    from stsf_gym.envs.config import read_yaml

    world = {**read_yaml(CONFIG_DIR / "worlds" / "straight_10m.yaml"), **route}
    env = PoseEstimateWrapper(
        make_env("stsf_gym/Corridor-v0", world=world, task=STOP_TASK, **NO_CAMERA), "truth"
    )
    env.reset(seed=0, options={"start_pose": [3.0, 0.0, 0.0]})
    held = DecisionInterval(env, 5)
    *_, terminated, _, info = held.step(np.array([0.0, 0.0, 1.0], np.float32))
    assert info["stops"] == 1 and info["last_stop"]["success"]  # the first goal, declared once
    assert not terminated and info["control_steps"] == 5


def _layers(env, bottom) -> list[str]:
    names = []
    while env is not bottom and hasattr(env, "env"):
        names.append(type(env).__name__)
        env = env.env
    return names


def test_training_and_evaluation_build_the_same_policy_stack(make_env, tmp_path, monkeypatch):
    import types

    from stsf_gym.agents import model_files
    from stsf_gym.agents.training.train import make_training_env

    settings = {"task": STOP_TASK, "camera": {"enabled": False}}
    trained = make_training_env(
        "straight_10m", "truth", settings, {}, 5, str(tmp_path / "m"), in_worker=False
    )
    inner = trained
    while not isinstance(inner, CameraPointingWrapper):  # the episode env's outermost wrapper
        inner = inner.env
    assert _layers(trained, inner) == ["Monitor", "DecisionInterval", "PolicyObservation"]
    agent = SB3Agent.__new__(SB3Agent)  # as loaded from a model trained with this stack
    agent.path, agent.meta = tmp_path / "model.zip", {"observation": {}, "decision_steps": 5}
    model = types.SimpleNamespace(
        observation_space=trained.observation_space, action_space=trained.action_space
    )
    monkeypatch.setattr(model_files, "load_model", lambda path: model)
    env = PoseEstimateWrapper(
        make_env("stsf_gym/Straight10m-v0", task=STOP_TASK, **NO_CAMERA), "truth"
    )
    assert _layers(agent.wrap(env), env) == ["DecisionInterval", "PolicyObservation"]
    trained.close()
    follower = make_agent("follower", {"decision_steps": 5})
    assert isinstance(follower, FollowerAgent)
    assert isinstance(follower.wrap(env), DecisionInterval)
    with pytest.raises(ConfigError, match="unknown agent"):
        make_agent("nobody")


def test_a_registered_agent_is_made_by_its_name():
    from stsf_gym.agents.registry import AGENTS, register_agent

    register_agent("slow-follower", lambda **o: FollowerAgent(decision_steps=2, **o))
    try:
        agent = make_agent("slow-follower")
        assert isinstance(agent, FollowerAgent) and agent.label() == "follower-k2"
    finally:
        del AGENTS["slow-follower"]
    with pytest.raises(ValueError, match="may not contain"):
        register_agent("pkg.mod:Class", FollowerAgent)
