import gymnasium as gym
import numpy as np
import pytest
from helpers import drive

ACTIONS = [[0.5, 0.2]] * 12 + [[0.8, -0.4]] * 12


def _run(env, seed):
    return drive(env, ACTIONS, seed=seed)


def _assert_same(a, b):
    for (obs_a, info_a), (obs_b, info_b) in zip(a, b, strict=True):
        for key in obs_a:
            np.testing.assert_array_equal(obs_a[key], obs_b[key], err_msg=key)
        np.testing.assert_array_equal(info_a["true_pose"], info_b["true_pose"])
        np.testing.assert_array_equal(info_a["camera_pose"], info_b["camera_pose"])


def test_same_seed_same_actions_identical(make_env):
    env = make_env()
    first = _run(env, seed=3)
    _run(env, seed=99)  # something else in between must not leak into the next episode
    second = _run(env, seed=3)
    _assert_same(first, second)
    drive(env, [[-1.0, 1.0]], seed=7, options={"start_pose": [1.0, 0.3, 0.2]})  # a short one
    _assert_same(first, _run(env, seed=3))
    fresh = make_env()
    _assert_same(first, _run(fresh, seed=3))


def test_different_seeds_differ(make_env):
    env = make_env()
    a, b = _run(env, seed=1), _run(env, seed=2)
    sonar_a = np.array([obs["sonar"] for obs, _ in a])
    sonar_b = np.array([obs["sonar"] for obs, _ in b])
    assert not np.array_equal(sonar_a, sonar_b)
    assert env.unwrapped.odometry_calibration != _calibration_for_seed(env, 1)


def _calibration_for_seed(env, seed):
    env.reset(seed=seed)
    return env.unwrapped.odometry_calibration


@pytest.mark.slow
def test_two_envs_in_one_process_do_not_interfere(make_env):
    alone = _run(make_env(), seed=5)
    env_a, env_b = make_env(), make_env(camera__renderer="tiny")
    env_a.reset(seed=5)
    env_b.reset(seed=6)
    interleaved = [env_a.reset(seed=5)]
    for action in ACTIONS:
        obs, _, _, _, info = env_a.step(np.asarray(action, np.float32))
        env_b.step(np.asarray([1.0, 1.0], np.float32))  # a different robot moving meanwhile
        interleaved.append((obs, info))
    _assert_same(alone, interleaved)


@pytest.mark.slow
def test_async_vector_env_of_four():
    env_fns = [(lambda: gym.make("stsf_gym/Corridor-v0", camera__enabled=False)) for _ in range(4)]
    vec = gym.vector.AsyncVectorEnv(env_fns)
    try:
        obs, infos = vec.reset(seed=[10, 11, 12, 13])
        for _ in range(10):
            obs, _, _, _, infos = vec.step(np.tile(np.float32([0.6, 0.0]), (4, 1)))
        poses = infos["true_pose"]
        # identical robots driven identically travel identically; sensor noise differs by seed
        np.testing.assert_allclose(poses, np.repeat(poses[:1], 4, axis=0), atol=1e-9)
        assert len({obs["sonar"][i].tobytes() for i in range(4)}) == 4
    finally:
        vec.close()
    serial = gym.make("stsf_gym/Corridor-v0", camera__enabled=False)
    history = drive(serial, [[0.6, 0.0]] * 10, seed=12)
    serial.close()
    np.testing.assert_array_equal(history[-1][1]["true_pose"], poses[2])
    np.testing.assert_array_equal(history[-1][0]["sonar"], obs["sonar"][2])


@pytest.mark.slow
def test_forked_workers_fall_back_from_egl_and_forkserver_keeps_it():
    """EGL deadlocks in a process forked after its parent loaded it: workers fall back."""
    parent = gym.make("stsf_gym/Corridor-v0")
    parent_renderer = parent.unwrapped.renderer
    parent.close()

    def make():  # the module prefix imports stsf_gym in fresh (forkserver) workers
        return gym.make("stsf_gym:stsf_gym/Corridor-v0", camera__width=64, camera__height=48)

    for context, expected in (("fork", "tiny"), ("forkserver", parent_renderer)):
        vec = gym.vector.AsyncVectorEnv([make, make], context=context)
        try:
            vec.reset(seed=[0, 1])
            obs, *_ = vec.step(np.zeros((2, 2), np.float32))
            assert vec.get_attr("renderer") == (expected, expected)
            assert obs["image"].shape == (2, 48, 64, 3) and obs["image"].std() > 0
        finally:
            vec.close()
