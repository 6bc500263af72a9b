"""What an env is handed, refused at the door in one line: keyword arguments it does not take
(a ``TypeError``, as Python and Gymnasium raise), a section given a value, actions of the wrong
kind, reset options that are no mapping, an observation scale of 0, a lens the undistortion
cannot undo, a decoy board on no wall, actions of the wrong shape or value, a step, reset or
render after close(), and a start pose off the corridor."""

from __future__ import annotations

import re

import gymnasium as gym
import numpy as np
import pytest

from stsf_gym.agents.observation import observation_config
from stsf_gym.envs.config import load_config
from stsf_gym.validation import ConfigError
from stsf_gym.wrappers import CameraPointingWrapper, PoseEstimateWrapper

IDS = ["stsf_gym/Corridor-v0", "stsf_gym/Generated-v0", "stsf_gym/Suite-Sparse-STSF-v0"]
NO_CAMERA = {"camera": {"enabled": False}}


@pytest.mark.parametrize("env_id", IDS)
def test_an_unknown_keyword_raises_the_type_error_python_raises(env_id):
    with pytest.raises(TypeError, match="unexpected keyword argument 'frameskip'") as raised:
        gym.make(env_id, frameskip=4)
    assert isinstance(raised.value, ConfigError)  # the command line's one-line error too


@pytest.mark.parametrize("env_id", IDS)
def test_a_bad_value_of_a_known_keyword_stays_a_config_error(env_id):
    with pytest.raises(ConfigError, match=r"camera\.mode must be one of") as raised:
        gym.make(env_id, camera__mode="fastest")
    assert not isinstance(raised.value, TypeError)


def test_torchrl_style_retry_without_frameskip_makes_the_env():
    """TorchRL's ``GymEnv`` passes ``frameskip`` and retries without it on exactly this
    ``TypeError`` (the message naming the keyword); any other error is raised."""

    def make_like_torchrl(env_id: str, **kwargs):
        try:
            return gym.make(env_id, frameskip=1, **kwargs)
        except TypeError as err:
            if "unexpected keyword argument 'frameskip'" not in str(err):
                raise
            return gym.make(env_id, **kwargs)

    env = make_like_torchrl("stsf_gym/Suite-Corridor-Truth-v0", **NO_CAMERA)
    try:
        env.reset(seed=0)
        env.step(np.zeros(env.action_space.shape, np.float32))
    finally:
        env.close()


@pytest.mark.parametrize("env_id", IDS)
def test_a_section_given_a_value_is_named(env_id):
    with pytest.raises(ConfigError, match="camera is a section: it must be a mapping of its keys"):
        gym.make(env_id, camera="fast")


def test_a_section_given_a_value_on_the_command_line_is_one_line(run_cli, tmp_path):
    code, err = run_cli(
        "evaluate", "--set", "camera=fast", "--seeds", "1", "--out", str(tmp_path / "o")
    )
    assert code == 2 and "camera is a section" in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    "action", [np.ones(3, bool), np.ones(3, complex), np.array(["1", "1", "0"])]
)
@pytest.mark.parametrize(
    "env_id", ["stsf_gym/Suite-Corridor-Truth-v0", "stsf_gym/Suite-Corridor-v0"]
)
def test_an_action_of_the_wrong_kind_is_refused_not_cast(make_env, env_id, action):
    env = make_env(env_id, **NO_CAMERA)
    env.reset(seed=0)
    before = env.unwrapped.robot.floor_pose().copy()
    with pytest.raises(ValueError, match=f"action must be numeric .*got dtype {action.dtype}"):
        env.step(action)
    assert np.array_equal(env.unwrapped.robot.floor_pose(), before)  # not driven at full speed


@pytest.mark.parametrize("options", ["abc", ["start_pose"], 3])
@pytest.mark.parametrize(
    "env_id", ["stsf_gym/Corridor-v0", "stsf_gym/Corridor-Odometry-v0", "stsf_gym/Generated-v0"]
)
def test_reset_options_that_are_no_mapping_are_named(make_env, env_id, options):
    env = make_env(env_id, **NO_CAMERA)
    with pytest.raises(ValueError, match=re.escape(f"or None, got {options!r}")):
        env.reset(seed=0, options=options)


def test_an_observation_scale_of_zero_is_refused():
    for scale in (0, -1.0):
        with pytest.raises(ConfigError, match=r"observation\.scale must be > 0"):
            observation_config({"scale": scale})


def test_a_lens_the_undistortion_cannot_undo_is_refused():
    with pytest.raises(ConfigError, match=r"camera\.lens\.distortion .* cannot be undone"):
        load_config(camera={"lens": {"distortion": [1e6, 0, 0, 0, 0]}})
    for profile in ("ideal", "paper"):  # the shipped lenses stay valid
        load_config(camera={"profile": profile})


def test_a_decoy_board_on_no_wall_is_refused():
    decoy = {"kind": "outlier_detection", "start": 1.0, "duration": 1.0, "landmark_id": 7}
    with pytest.raises(ConfigError, match=r"faults\[0\].at must lie on a wall centre line"):
        load_config(world="irl_corridor", faults=[{**decoy, "at": [7.0, 0.0], "facing_deg": 90.0}])
    with pytest.raises(ConfigError, match=r"faults\[0\].facing_deg must face straight out"):
        load_config(world="irl_corridor", faults=[{**decoy, "at": [7.0, -0.8], "facing_deg": 45.0}])
    load_config(world="irl_corridor", config="configs/faults/outlier_detection.yaml")


# --- a closed env, a refused reset, a start pose, a batch of actions -------------------------

FAST = {"camera": {"mode": "fast"}}


AFTER_CLOSE_IDS = [
    "stsf_gym/Corridor-v0",
    "stsf_gym/Corridor-Truth-v0",
    "stsf_gym/Suite-Corridor-Truth-v0",
]


def after_close(env: gym.Env, call: str) -> None:
    """Make ``call`` (``step``, ``reset``, ``render``) on a closed ``env``."""
    if call == "step":
        env.step(env.action_space.sample())
    elif call == "reset":
        env.reset(seed=0)
    else:
        env.render()


@pytest.mark.parametrize("env_id", AFTER_CLOSE_IDS)
@pytest.mark.parametrize("render_mode", [None, "rgb_array"])
@pytest.mark.parametrize("call", ["step", "reset", "render"])
def test_a_call_after_close_says_the_env_is_closed(make_env, env_id, render_mode, call):
    env = make_env(env_id, render_mode=render_mode, **FAST)
    env.reset(seed=0)
    env.close()
    with pytest.raises(RuntimeError, match=f"^{call}\\(\\) after close\\(\\): this env is closed"):
        after_close(env, call)
    env.close()  # a second close is a no-op, and so is the fixture's third


@pytest.mark.parametrize("call", ["step", "reset", "render"])
def test_a_hand_built_stack_after_close_says_the_env_is_closed(call):
    pan = {"camera": {"mode": "fast", "control": "pan"}}
    env = gym.make("stsf_gym/Corridor-v0", render_mode="rgb_array", **pan).unwrapped
    stack = CameraPointingWrapper(PoseEstimateWrapper(env, "odometry"))  # no OrderEnforcing
    stack.close()
    with pytest.raises(RuntimeError, match=f"^{call}\\(\\) after close\\(\\): this env is closed"):
        after_close(stack, call)  # the env's words, not a wrapper's AttributeError
    stack.close()


def test_a_refused_first_reset_leaves_the_env_stepping_after_a_valid_one(make_env):
    env = make_env("stsf_gym/Corridor-v0", **FAST)
    with pytest.raises(ValueError, match="start_pose must be inside the walls' bounds"):
        env.reset(seed=0, options={"start_pose": [1e5, 0.0, 0.0]})
    env.reset(seed=0)
    *_, info = env.step(env.action_space.sample())
    assert info["sim_time"] > 0


@pytest.mark.parametrize(
    ("start", "said"),
    [
        ([7.0, 5.0, 0.0], "is outside the corridor: walls part it from the path's start"),
        ([0.0, 0.0, 1e12], "yaw must be an angle in radians within ±12.57 (two turns), got 1e+12"),
        ([0.0, 0.0, float("inf")], "must be three finite numbers"),
    ],
)
def test_a_start_pose_off_the_corridor_or_with_an_absurd_yaw_is_refused(make_env, start, said):
    env = make_env("stsf_gym/Corridor-v0", **FAST)  # the IRL corridor: an L round [7, 5]
    with pytest.raises(ValueError, match=re.escape(said)):
        env.reset(seed=0, options={"start_pose": start})
    _, info = env.reset(seed=0, options={"start_pose": [7.0, 0.0, 2 * np.pi]})  # in the corridor
    assert info["true_pose"][:2] == pytest.approx([7.0, 0.0], abs=0.01)


@pytest.mark.parametrize(
    "env_id",
    [
        "stsf_gym/Corridor-v0",
        "stsf_gym/Corridor-Odometry-v0",  # the pointing wrapper fills in the pan entry
        "stsf_gym/Suite-Corridor-Odometry-v0",
        "stsf_gym/RL-Corridor-Odometry-v0",  # the decision interval holds the action
    ],
)
def test_an_action_of_a_batch_shape_is_refused_with_the_expected_shape(make_env, env_id):
    env = make_env(env_id, **FAST)
    env.reset(seed=0)
    before = env.unwrapped.robot.floor_pose().copy()
    n = env.action_space.shape[0]
    with pytest.raises(ValueError, match=re.escape(f"action must have shape ({n},), got (1, {n})")):
        env.step(np.zeros((1, n), np.float32))
    assert np.array_equal(env.unwrapped.robot.floor_pose(), before)  # refused before a step


def test_an_action_of_the_wrong_kind_is_refused_under_the_decision_interval(make_env):
    env = make_env("stsf_gym/RL-Corridor-Odometry-v0", **FAST)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"action must be numeric .*got dtype bool"):
        env.step(np.ones(env.action_space.shape, bool))  # not cast to full speed


# --- actions ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("action", "message"),
    [
        ([np.nan, 0.0], "NaN or infinite"),
        ([0.5, np.inf], "NaN or infinite"),
        ([0.5, 0.0, 0.1], r"shape \(2,\)"),
        ([[0.5, 0.0]], r"shape \(2,\), got \(1, 2\)"),  # a batch of one is not flattened
        (["0.5", "0.0"], "must be numeric"),
        (np.array([0.5, None], dtype=object), "must be numeric"),
        ([True, False], "must be numeric"),
        ("forward", "must be numeric"),
    ],
)
def test_bad_actions_raise_clear_errors(make_env, action, message):
    env = make_env(camera__enabled=False)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(action)


def test_out_of_range_actions_are_clipped(make_env):
    env = make_env(camera__enabled=False)
    poses = []
    for action in ([1.0, -1.0], [7.5, -30.0]):
        env.reset(seed=4)
        for _ in range(10):
            *_, info = env.step(np.float32(action))
        poses.append(info["true_pose"])
    np.testing.assert_array_equal(poses[0], poses[1])
    env.reset(seed=4)
    for _ in range(10):
        *_, info = env.step(np.float32([0.5, 0.0]))
    assert not np.array_equal(info["true_pose"], poses[0])  # the action does matter
