"""The declared-arrival reward's optimum is the task: on hand-built episodes of true positions
along a straight 10 m path, a correct declaration has the best return, dawdling to the time limit
is not paid, a false stop is never better than trying on, no metre of a leg is paid twice, and a
reward config for which any of these fails is refused under the declare protocol."""

import numpy as np
import pytest

from stsf_gym.envs.config import load_config
from stsf_gym.envs.task import PathTask
from stsf_gym.validation import ConfigError

DT = 0.5  # s per hand-built step
TIME_LIMIT = 150.0  # s: the training legs' limit (configs/agents/ppo.yaml)
GOAL_ARC = 5.0  # m along the path (x, on straight_10m)
TASK = {"protocol": "declare", "stop_action": True}


def leg_task() -> tuple[PathTask, object]:
    cfg = load_config(world="straight_10m", task=TASK, sim={"max_episode_seconds": TIME_LIMIT})
    task = PathTask(cfg.world, cfg.reward, cfg.task)
    task.set_goals([[GOAL_ARC, 0.0]])
    return task, cfg


def episode_return(xs: list[float], stop_at_end: bool) -> float:
    """The return of the robot at true positions ``(x, 0)`` step by step (the env's order: the
    task judges the step, then progress and reward), declaring at the last one if asked; the
    episode is cut at the time limit as the env cuts it."""
    task, _ = leg_task()
    progress, total, time = task.progress(np.array([xs[0], 0.0])), 0.0, 0.0
    for i, x in enumerate(xs[1:], 1):
        time += DT
        xy = np.array([x, 0.0])
        reached = task.update(xy, 0.1, 0.0, DT, time, stop=stop_at_end and i == len(xs) - 1)
        now = task.progress(xy)
        total += task.reward(now - progress, DT, reached, False)
        progress = now
        if task.finished or time >= TIME_LIMIT - 1e-9:
            break
    return total


def drive(start: float, end: float, speed: float = 0.122) -> list[float]:
    steps = max(int(abs(end - start) / (speed * DT)), 1)
    return list(np.linspace(start, end, steps + 1))


def wait(x: float, seconds: float) -> list[float]:
    return [x] * int(seconds / DT)


def test_correct_stops_differ_by_their_offset_along_the_path_a_false_one_by_the_bonus():
    short, exact, past = (episode_return(drive(1.0, GOAL_ARC + d), True) for d in (-0.2, 0, 0.2))
    steps = len(drive(1.0, GOAL_ARC)) - 1
    assert exact == pytest.approx(4.0 + 10.0 - 0.01 * DT * steps)
    for correct in (short, past):  # within 0.2 m of progress and a step or so of time
        assert abs(correct - exact) <= 0.2 + 4 * 0.01 * DT
    missed = episode_return(drive(1.0, GOAL_ARC - 0.3), True)  # 0.3 m short: off the radius
    assert missed < short - 10.0 + 0.2


def test_a_correct_declaration_beats_dawdling_to_the_time_limit():
    declared = episode_return(drive(1.0, GOAL_ARC), True)
    dawdled = episode_return(drive(1.0, GOAL_ARC) + wait(GOAL_ARC, TIME_LIMIT), False)
    late = episode_return(drive(1.0, GOAL_ARC) + wait(GOAL_ARC, 60.0), True)
    assert dawdled < late < declared  # waiting costs, and not declaring forgoes the goal


def test_a_false_stop_is_never_better_than_trying_on():
    short = drive(1.0, GOAL_ARC - 1.0)  # 1 m short: outside the 0.25 m radius
    false_stop = episode_return(short, True)
    stand_to_the_limit = episode_return(short + wait(GOAL_ARC - 1.0, TIME_LIMIT), False)
    go_on = episode_return(short + drive(GOAL_ARC - 1.0, GOAL_ARC)[1:], True)
    assert false_stop < stand_to_the_limit < go_on


def test_no_metre_of_a_leg_is_paid_twice():
    straight = episode_return(drive(1.0, GOAL_ARC), True)
    to_and_fro = drive(1.0, 3.0) + drive(3.0, 2.0)[1:] + drive(2.0, 4.0)[1:]
    there_and_back = drive(1.0, 7.0) + drive(7.0, GOAL_ARC)[1:]  # past the goal and back
    for xs in (to_and_fro + drive(4.0, GOAL_ARC)[1:], there_and_back):
        detour = (len(xs) - len(drive(1.0, GOAL_ARC))) * DT * 0.01
        assert episode_return(xs, True) == pytest.approx(straight - detour, abs=1e-9)


def test_the_reward_never_reads_anything_but_the_true_stop():
    """The goal is judged at the true position: a stop 0.3 m off fails, 0.2 m off succeeds,
    whatever the agent believed (the task gets no estimate)."""
    task, _ = leg_task()
    assert not task.update(np.array([GOAL_ARC - 0.3, 0.0]), 0.0, 0.0, DT, 1.0, stop=True)
    task, _ = leg_task()
    assert task.update(np.array([GOAL_ARC - 0.2, 0.0]), 0.0, 0.0, DT, 1.0, stop=True)


@pytest.mark.parametrize(
    ("reward", "key"),
    [
        ({"time": 0.0}, "reward.time"),
        ({"goal": 0.0}, "reward.goal"),
        ({"false_stop": -1.0}, "reward.false_stop"),  # -1 > -0.01 * 150: a stop would pay
    ],
)
def test_a_reward_whose_optimum_is_not_the_task_is_refused(reward, key):
    with pytest.raises(ConfigError, match=key):
        load_config(
            world="straight_10m", task=TASK, reward=reward, sim={"max_episode_seconds": 150.0}
        )
    load_config(world="straight_10m", reward=reward)  # reach: the paper's protocol, unchanged


GOES_ON = {**TASK, "false_stop_ends": False}


def goes_on_return(
    xs: list[float], stops_at: set[int], design: str = "stop-goes-on"
) -> tuple[float, bool]:
    """The return (and success) on a training leg of declaration ``design`` (a false stop
    goes on: ``task.false_stop_ends: false``), declaring at the steps ``stops_at``."""
    from stsf_gym.agents.rl.declaration import declaration

    cfg = load_config(
        world="straight_10m", task=GOES_ON, reward=declaration(design).training_env()["reward"],
        sim={"max_episode_seconds": TIME_LIMIT},
    )  # fmt: skip
    task = PathTask(cfg.world, cfg.reward, cfg.task)
    task.set_goals([[GOAL_ARC, 0.0]])
    progress, total, time = task.progress(np.array([xs[0], 0.0])), 0.0, 0.0
    for i, x in enumerate(xs[1:], 1):
        time += DT
        xy = np.array([x, 0.0])
        reached = task.update(xy, 0.1, 0.0, DT, time, stop=i in stops_at)
        now = task.progress(xy)
        total += task.reward(now - progress, DT, reached, False)
        progress = now
        if task.finished or time >= TIME_LIMIT - 1e-9:
            break
    return total, task.success


@pytest.mark.parametrize(
    "design",
    ["stop-goes-on", "stop-cheap", "discrete-cheap", "stop-cheap-first", "stop-cheap-rare"],
)
def test_under_the_training_rule_a_false_stop_costs_goes_on_and_never_pays(design):
    from stsf_gym.agents.rl.declaration import declaration

    xs = drive(1.0, GOAL_ARC)
    last = len(xs) - 1
    correct, ok = goes_on_return(xs, {last}, design)
    tried_early, ok_early = goes_on_return(xs, {3, last}, design)
    spammed, ok_spam = goes_on_return(xs, set(range(1, last + 1)), design)
    never, ok_never = goes_on_return(xs, set(), design)
    assert ok and ok_early and ok_spam and not ok_never  # a false stop ends nothing
    cost = -declaration(design).false_stop
    assert correct - tried_early == pytest.approx(cost)  # each false stop costs the design's
    assert spammed < tried_early < correct and never < correct


def test_the_cheap_false_stop_sits_in_the_window_its_module_derives():
    from stsf_gym.agents.rl.declaration import CHEAP_FALSE_STOP

    goal, radius, speed, period, longest = 10.0, 0.25, 0.122, 0.5, 10.0
    inside = 2 * radius / speed / period  # decisions within the radius passing through a goal
    leg = longest / speed / period  # decisions of the longest leg
    assert goal / leg < -CHEAP_FALSE_STOP < goal * inside / leg


def test_a_false_stop_that_goes_on_must_cost_something():
    with pytest.raises(ConfigError, match=r"reward\.false_stop"):
        load_config(world="straight_10m", task=GOES_ON, reward={"false_stop": 0.0})
    with pytest.raises(ConfigError, match="protocol"):
        load_config(world="straight_10m", task={"false_stop_ends": False})
