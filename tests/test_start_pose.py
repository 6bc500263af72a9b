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
