"""``reset(options={"start_pose": ...})`` is checked like the configured start."""

import numpy as np
import pytest


@pytest.mark.parametrize(
    ("start_pose", "problem"),
    [
        ([100.0, 100.0, 0.0], "start_pose must be inside the walls' bounds"),
        (
            [2.0, 0.7, 0.0],
            r"start_pose must be at least robot.body_radius \(0.25 m\) from every wall",
        ),
        ([2.0, 0.0, float("nan")], r"start_pose must be three finite numbers"),
        ([2.0, 0.0], r"start_pose must be three finite numbers"),
        ([2.0, 0.0, 0.0, 1.0], r"start_pose must be three finite numbers"),
        ("here", r"start_pose must be three finite numbers"),
    ],
)
def test_bad_start_pose_is_rejected_naming_it(make_env, start_pose, problem):
    env = make_env(camera__enabled=False)
    with pytest.raises(ValueError, match=problem):
        env.reset(seed=0, options={"start_pose": start_pose})
    _, info = env.reset(seed=0, options={"start_pose": [2.0, 0.3, 0.5]})  # still usable
    np.testing.assert_allclose(info["true_pose"], [2.0, 0.3, 0.5], atol=1e-6)


def test_start_pose_must_clear_the_clutter(make_env):
    env = make_env(world="irl_corridor_cluttered", camera__enabled=False)
    with pytest.raises(ValueError, match=r"start_pose .* obstacles\[0\] is 0.000 m away"):
        env.reset(seed=0, options={"start_pose": [4.5, 0.45, 0.0]})
    env.reset(seed=0, options={"start_pose": [4.5, -0.3, 0.0]})  # beside the box: fine


def test_estimating_wrapper_rejects_a_bad_start_pose(make_env):
    env = make_env("stsf_gym/Corridor-Odometry-v0", camera__enabled=False)
    with pytest.raises(ValueError, match="start_pose must be inside"):
        env.reset(seed=0, options={"start_pose": [100.0, 100.0, 0.0]})


SPREAD = {"start_along": 2.0, "start_lateral": 0.3, "start_yaw_deg": 20.0}


def test_drawn_start_poses_stay_in_their_ranges_and_follow_the_seed(make_env):
    from stsf_gym.envs.task import Polyline

    env = make_env("stsf_gym/Corridor-EKF-v0", camera__mode="fast", task=SPREAD)
    path = Polyline(env.unwrapped.config.world.path)
    starts = []
    for seed in range(12):
        obs, info = env.reset(seed=seed)
        x, y, yaw = env.unwrapped.start_pose
        along = path.project((x, y))
        assert 0.0 <= along <= 2.0
        lateral = np.linalg.norm(np.array([x, y]) - path.point_at(along))
        assert lateral <= 0.3 + 1e-9
        turn = np.degrees(np.remainder(yaw - path.heading_at(along) + np.pi, 2 * np.pi) - np.pi)
        assert abs(turn) <= 20.0 + 1e-6
        np.testing.assert_allclose(info["true_pose"], [x, y, yaw], atol=1e-6)  # put there
        np.testing.assert_allclose(obs["pose"], [x, y, yaw], atol=1e-5)  # estimators start there
        starts.append(env.unwrapped.start_pose.copy())
    assert len({tuple(np.round(s, 6)) for s in starts}) == len(starts)  # a new pose per seed
    env.reset(seed=3)
    np.testing.assert_array_equal(env.unwrapped.start_pose, starts[3])  # the same seed: the same


def test_no_spread_keeps_the_worlds_start(make_env):
    env = make_env(camera__enabled=False)
    _, info = env.reset(seed=5)
    np.testing.assert_allclose(env.unwrapped.start_pose, env.unwrapped.config.world.start)
    np.testing.assert_allclose(
        info["true_pose"][:2], env.unwrapped.config.world.start[:2], atol=1e-6
    )


def test_a_start_range_past_the_first_goal_is_rejected_naming_the_key(make_env):
    env = make_env("stsf_gym/Straight10m-v0", camera__enabled=False, task={"start_along": 12.0})
    with pytest.raises(ValueError, match=r"task.start_along must leave the first goal ahead"):
        env.reset(seed=0)
    too_wide = make_env(camera__enabled=False, task={"start_lateral": 3.0})
    problem = r"task.start_lateral 3 m across the path at 0 m along it puts the robot into"
    with pytest.raises(ValueError, match=problem):
        too_wide.reset(seed=0)
