"""The policy's input follows each episode's path from the reset's ``info["path"]``, to the
bit as it did when it read ``env.unwrapped.config.world`` at every step."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from stsf_gym.agents.observation import PolicyObservation
from stsf_gym.agents.rl.map_view import MapView
from stsf_gym.envs.task import Polyline

SEEDS, STEPS = (0, 1, 2, 1), 4


def policy_wrapper(env: gym.Env) -> PolicyObservation:
    """The :class:`PolicyObservation` in ``env``'s stack."""
    while isinstance(env, gym.Wrapper):
        if isinstance(env, PolicyObservation):
            return env
        env = env.env
    raise AssertionError("no PolicyObservation in the stack")


def record_against_world(policy: PolicyObservation) -> list[tuple[np.ndarray, np.ndarray]]:
    """Make ``policy`` keep each input it gives beside the one of the former logic: the path
    (and map) rebuilt from ``env.unwrapped.config.world`` whenever that world changes."""
    reference = PolicyObservation(policy.env, policy.config)
    uses_map = policy.config.boards or policy.config.predicted_sonar
    seen: list[object] = [None]
    pairs: list[tuple[np.ndarray, np.ndarray]] = []
    given = policy.observation

    def observation(obs: dict) -> np.ndarray:
        world = policy.env.unwrapped.config.world
        if world is not seen[0]:
            seen[0], reference.path = world, Polyline(world.path)
            reference.map_view = MapView(policy.env, policy.config.scale) if uses_map else None
        pairs.append((given(obs), reference.observation(obs)))
        return pairs[-1][0]

    policy.observation = observation  # type: ignore[method-assign]
    return pairs


def drive(env: gym.Env) -> list[np.ndarray]:
    """Episodes of :data:`SEEDS`, :data:`STEPS` decisions each; the paths they ran on."""
    paths = []
    for seed in SEEDS:
        _, info = env.reset(seed=seed)
        paths.append(info["path"])
        for _ in range(STEPS):
            action = np.zeros_like(env.action_space.sample())
            action[0] = 0.5
            *_, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                break
    return paths


@pytest.mark.parametrize(
    ("env_id", "observation"),
    [
        ("stsf_gym/RL-Sparse-STSF-v0", None),
        ("stsf_gym/RL-Corridor-Truth-v0", None),
        ("stsf_gym/Suite-Sparse-Truth-v0", {"boards": 2, "predicted_sonar": True}),
    ],
)
def test_the_input_equals_the_one_read_from_the_world_as_worlds_change(
    make_env, env_id, observation
):
    env = make_env(env_id)
    if observation is not None:
        env = PolicyObservation(env, observation)
    pairs = record_against_world(policy_wrapper(env))
    paths = drive(env)
    assert len({p.tobytes() for p in paths}) == 3  # a new world at each new seed
    assert len(pairs) > len(SEEDS)
    for step, (mine, former) in enumerate(pairs):
        assert mine.tobytes() == former.tobytes(), f"input {step}"


def test_the_path_in_info_is_the_worlds_through_the_episode(make_env):
    env = make_env("stsf_gym/Suite-Sparse-Truth-v0")
    _, info = env.reset(seed=0)
    np.testing.assert_array_equal(info["path"], env.unwrapped.config.world.path)
    assert info["path"].dtype == np.float64 and info["path"].shape[1] == 2
    *_, step_info = env.step(np.zeros_like(env.action_space.sample()))
    np.testing.assert_array_equal(step_info["path"], info["path"])
