"""The robot a roboticist would trust: a level chassis, wheels through acceleration limits,
and dead reckoning on perfect encoders that follows the truth under RL-style commands."""

import math

import numpy as np
import pytest
from helpers import NOISE_FREE_ENCODERS

from stsf_gym.envs.config import load_config
from stsf_gym.envs.drive_controller import VelocityController
from stsf_gym.estimators.odometry_model import integrate_wheel_travel

STRAIGHT = "stsf_gym/Straight10m-v0"


def floor_transform(pose):
    x, y, yaw = pose
    transform = np.eye(4)
    transform[:3, :3] = [
        [math.cos(yaw), -math.sin(yaw), 0],
        [math.sin(yaw), math.cos(yaw), 0],
        [0, 0, 1],
    ]
    transform[:3, 3] = (x, y, 0.0)
    return transform


def mount_error(env, info):
    """Distance (m) and angle (rad) between the camera's true pose and ``true_pose`` composed
    with the nominal robot-from-camera of the measured mount angles."""
    unwrapped = env.unwrapped
    nominal = floor_transform(info["true_pose"]) @ unwrapped.robot_from_camera(
        *unwrapped.robot.mount_angles()
    )
    actual = unwrapped.robot.camera_pose()
    rotation = nominal[:3, :3].T @ actual[:3, :3]
    angle = math.acos(np.clip((np.trace(rotation) - 1) / 2, -1.0, 1.0))
    return np.linalg.norm(nominal[:3, 3] - actual[:3, 3]), angle


def reversing_turns(forward: float, seconds: float = 30.0, period: float = 1.0, dt: float = 0.1):
    """Full-scale yaw commands whose sign flips every ``period`` seconds, the first leg half as
    long (so the rate-limited yaw rate swings symmetrically about zero and the robot weaves
    along the corridor instead of circling)."""
    per_leg = round(period / dt)
    return [
        [forward, 1.0 if ((k + per_leg // 2) // per_leg) % 2 == 0 else -1.0]
        for k in range(round(seconds / dt))
    ]


@pytest.mark.parametrize("forward", [0.0, 1.0], ids=["spin", "weave"])
def test_perfect_encoders_dead_reckon_within_1deg_and_1_percent(make_env, forward):
    env = make_env(STRAIGHT, camera__enabled=False, **NOISE_FREE_ENCODERS)
    _, info = env.reset(seed=0, options={"start_pose": [0.5, -0.85, -0.1]})
    calibration = env.unwrapped.odometry_calibration
    estimate, previous, distance, worst = info["true_pose"].copy(), info["true_pose"], 0.0, (0, 0)
    for action in reversing_turns(forward):
        obs, _, terminated, _, info = env.step(np.float32(action))
        assert not terminated
        estimate = integrate_wheel_travel(
            estimate, *calibration.wheel_travel(obs["encoders"]), calibration.wheelbase
        )
        distance += float(np.hypot(*(info["true_pose"][:2] - previous[:2])))
        previous = info["true_pose"]
        worst = np.maximum(worst, mount_error(env, info))
    assert abs(math.degrees(math.remainder(estimate[2] - info["true_pose"][2], math.tau))) < 1.0
    assert np.hypot(*(estimate[:2] - info["true_pose"][:2])) <= max(0.01 * distance, 0.005)
    assert worst[0] < 0.5e-3 and worst[1] < 0.5e-3  # the chassis stays level while it turns


def test_chassis_rests_level(make_env):
    env = make_env(camera__enabled=False)
    env.reset(seed=0)
    for _ in range(10):  # standing still, then a step of full speed
        _, _, _, _, info = env.step(np.float32([0.0, 0.0]))
    distance, angle = mount_error(env, info)
    assert distance < 0.5e-3 and angle < 0.5e-3
    for _ in range(10):
        _, _, _, _, info = env.step(np.float32([1.0, 0.0]))
        assert max(mount_error(env, info)) < 0.5e-3


def test_velocity_controller_ramps_within_its_acceleration_limits():
    robot = load_config().robot
    controller, dt = VelocityController(robot), 1 / 120
    commands = [controller.update(np.array([robot.max_speed, -robot.max_yaw_rate]), dt)]
    commands += [
        controller.update(np.array([-robot.max_speed, robot.max_yaw_rate]), dt) for _ in range(400)
    ]
    changes = np.abs(np.diff(np.array(commands), axis=0)) / dt
    assert np.all(changes <= np.array([robot.max_acceleration, robot.max_yaw_acceleration]) + 1e-9)
    np.testing.assert_allclose(commands[-1], [-robot.max_speed, robot.max_yaw_rate])
    assert commands[0] == pytest.approx(
        [robot.max_acceleration * dt, -robot.max_yaw_acceleration * dt]
    )
    controller.reset()
    assert controller.update(np.array([5.0, 5.0]), 100.0) == (robot.max_speed, robot.max_yaw_rate)


def test_the_body_follows_the_ramp(make_env):
    """A full-speed command from rest: the truth accelerates at the controller's limit, not at
    once (the wheels roll, they do not skid)."""
    env = make_env(camera__enabled=False)
    _, info = env.reset(seed=0)
    start, steps = info["true_pose"][:2], 8  # 0.8 s: still accelerating (0.25 m/s at 0.83 s)
    for _ in range(steps):
        _, _, _, _, info = env.step(np.float32([1.0, 0.0]))
    limit = env.unwrapped.config.robot.max_acceleration
    expected = 0.5 * limit * (steps * env.unwrapped.dt) ** 2  # at the limit from rest
    assert np.hypot(*(info["true_pose"][:2] - start)) == pytest.approx(expected, rel=0.1)
