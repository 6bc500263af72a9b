import subprocess
import sys

import gymnasium as gym
import pytest

import stsf_gym


def test_ids_registered_and_registration_idempotent():
    for env_id in stsf_gym.ENV_WORLDS:
        assert env_id in gym.registry
    before = dict(gym.registry)
    stsf_gym.register_envs()
    assert dict(gym.registry).keys() == before.keys()


@pytest.mark.slow
def test_make_with_module_prefix_without_import():
    code = (
        "import gymnasium as gym\n"
        "env = gym.make('stsf_gym:stsf_gym/Corridor-v0', camera__enabled=False)\n"
        "obs, info = env.reset(seed=1)\n"
        "print('pose', info['true_pose'].tolist())\n"
        "env.close()\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert "pose [0.0, 0.0, 0.0]" in result.stdout


def test_straight_world_is_a_10m_path(make_env):
    env = make_env("stsf_gym/Straight10m-v0", camera__enabled=False)
    assert env.unwrapped.task.path.length == 10.0
    corridor = make_env("stsf_gym/Corridor-v0", camera__enabled=False)
    path = corridor.unwrapped.task.path
    assert path.length >= 20.0
    assert len(path.points) >= 3  # at least one turn
    assert len(corridor.unwrapped.landmarks) == 8
