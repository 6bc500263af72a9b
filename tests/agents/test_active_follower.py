"""The active follower's rule on hand-built observations, in a straight corridor with one board:
sure at the goal it declares as the follower; unsure with a board in sight it looks from there;
unsure with the board in sight only from a point of the route within the detour, it drives
there, looks, drives back and declares; with no board within reach it waits as the cautious
follower does."""

from __future__ import annotations

import math

import numpy as np
import pytest

from stsf_gym.agents import active_follower as af
from stsf_gym.agents import cautious_follower as cf
from stsf_gym.agents.follower import load_follower_config
from stsf_gym.estimators.base import MapLandmark
from stsf_gym.estimators.camera_pointing import LandmarkPointer

PATH = [[0.0, 0.0], [20.0, 0.0]]
WALLS = np.array([[0.0, -0.8, 20.0, -0.8], [0.0, 0.8, 20.0, 0.8]])
GOAL = 10.0
RADIUS, LIMIT, DT = 0.25, 600.0, 0.1
SURE, UNSURE = 0.5 * cf.SIGMA_SHARE * RADIUS, 2.0 * cf.SIGMA_SHARE * RADIUS


def board_at(x: float) -> MapLandmark:
    """A board on the north wall at ``x``, facing south into the corridor."""
    return MapLandmark(1, np.array([x, 0.75, 0.9]), np.array([0.0, -1.0, 0.0]), np.zeros((1, 3)))


def follower(board_x: float | None) -> af.ActiveFollower:
    f = af.ActiveFollower(PATH, load_follower_config(), 0.25, 1.0, None, True, 0, True)
    f.configure_caution(RADIUS, LIMIT, 0.1, DT)
    landmarks = {} if board_x is None else {1: board_at(board_x)}
    f.configure_activity(LandmarkPointer(landmarks, WALLS, 0.1, math.radians(170.0)))
    f.see_goal(GOAL, 1)
    return f


def act(f: af.ActiveFollower, pose, sigma: float) -> np.ndarray:
    f.observe(np.diag([sigma**2, sigma**2, 0.01]), 10.0)
    return f.act(np.asarray(pose, dtype=float))


def drive(f: af.ActiveFollower, pose, sure_after_detour: bool, steps: int = 3000):
    """Unicycle kinematics under the follower's commands, unsure until it has reached its
    viewpoint; the poses and the action at each step, until it declares."""
    pose, trace = np.asarray(pose, dtype=float), []
    for _ in range(steps):
        at_view = f._view_arc is not None and abs(pose[0] - f._view_arc) <= af.ARRIVED_M
        sure = sure_after_detour and (at_view or f._phase in (af.BACK, af.RETURNED))
        action = act(f, pose, SURE if sure else UNSURE)
        trace.append((pose.copy(), action))
        if action[2] == 1.0:
            break
        v, w = action[0] * 0.25, action[1] * 1.0
        pose = pose + DT * np.array([v * math.cos(pose[2]), v * math.sin(pose[2]), w])
    return trace


def test_sure_at_the_goal_it_declares_at_once():
    assert act(follower(11.2), [GOAL, 0.0, 0.0], SURE)[2] == 1.0


def test_unsure_with_a_board_in_sight_it_looks_from_where_it_stands():
    f = follower(11.2)  # 1.3 m off the camera, 34 deg off its normal: in sight from the goal
    for _ in range(20):
        action = act(f, [GOAL, 0.0, 0.0], UNSURE)
        assert action[2] == -1.0 and np.allclose(action[:2], 0.0)
    assert f.detours == 0
    assert act(f, [GOAL, 0.0, 0.0], SURE)[2] == 1.0


@pytest.mark.parametrize("board_x", [GOAL + 2.2, GOAL - 2.0])
def test_unsure_with_a_board_in_sight_only_nearby_it_goes_there_and_back(board_x):
    """Too oblique from the goal, in sight from a route point within the detour, ahead of the
    goal or behind it: there, sure once there, back, and declared at the goal."""
    f = follower(board_x)
    trace = drive(f, [GOAL, 0.0, 0.0], sure_after_detour=True)
    assert f.detours == 1 and abs(f._view_arc - GOAL) <= af.MAX_DETOUR_M
    xs = np.array([pose[0] for pose, _ in trace])
    farthest = xs[np.argmax(np.abs(xs - GOAL))]
    assert abs(farthest - f._view_arc) <= af.ARRIVED_M + 0.02  # it went to the viewpoint
    final, action = trace[-1]
    assert action[2] == 1.0 and abs(final[0] - GOAL) <= af.ARRIVED_M + 0.05


def test_it_declares_back_at_the_goal_when_the_look_is_spent_unsure():
    f = follower(GOAL + 2.2)
    trace = drive(f, [GOAL, 0.0, 0.0], sure_after_detour=False, steps=6000)
    final, action = trace[-1]
    assert f.detours == 1 and action[2] == 1.0 and abs(final[0] - GOAL) <= af.ARRIVED_M + 0.05
    assert f._waited == pytest.approx(f._budget, abs=DT)


def test_with_no_board_within_reach_it_waits_as_the_cautious_follower():
    f = follower(None)
    for _ in range(10):
        action = act(f, [GOAL, 0.0, 0.0], UNSURE)
        assert action[2] == -1.0 and np.allclose(action[:2], 0.0)
    assert f.detours == 0
    f._waited = f._budget  # the wait used up: it declares, sure or not
    assert act(f, [GOAL, 0.0, 0.0], UNSURE)[2] == 1.0


def test_the_agent_is_named_and_reports_its_constants():
    from stsf_gym.agents.registry import make_agent

    agent = make_agent("active-follower")
    assert agent.label() == "active-follower"
    assert agent.config()["activity"]["max_detour_m"] == af.MAX_DETOUR_M
