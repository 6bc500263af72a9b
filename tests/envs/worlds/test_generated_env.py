"""``stsf_gym/Generated-v0``: a world per reset, splits, world seeds, rebuilds, CLI."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import yaml
from helpers import drive

from stsf_gym.agents.observation import PolicyObservation
from stsf_gym.envs import generated_env
from stsf_gym.envs.worlds.generator import GenerationError, generate_world
from stsf_gym.envs.worlds.generator_config import load_generator_config

FAST = {"camera__mode": "fast"}
ACTIONS = [[1.0, 0.2]] * 15


def test_splits_are_disjoint_and_documented():
    gen = load_generator_config()
    train, test = gen.split_range("train"), gen.split_range("test")
    assert (train.start, len(train)) == (0, 1_000_000)
    assert (test.start, len(test)) == (1_000_000, 10_000)
    assert not set(range(test.start, test.start + 100)) & set(train)
    with pytest.raises(ValueError, match="split must be one of"):
        gen.split_range("validation")


def test_reset_seed_picks_the_splits_world(make_env):
    env = make_env("stsf_gym/Generated-v0", split="test", **FAST)
    worlds = []
    for seed in (3, 4, 3):
        env.reset(seed=seed)
        worlds.append((env.unwrapped.world_seed, env.unwrapped.config.world))
    assert [w for w, _ in worlds] == [1_000_003, 1_000_004, 1_000_003]
    assert worlds[0][1] == worlds[2][1] != worlds[1][1]
    assert env.unwrapped.landmarks[0].id == worlds[2][1].landmarks[0].id
    env.reset()  # unseeded: drawn from np_random, inside the split
    assert env.unwrapped.world_seed in range(1_000_000, 1_010_000)
    env.reset(options={"world_seed": 1_000_042})
    assert env.unwrapped.world_seed == 1_000_042
    with pytest.raises(ValueError, match=r"in the test split \[1000000, 1009999\], got 5"):
        env.reset(options={"world_seed": 5})


def test_train_split_never_gives_a_test_world(make_env):
    env = make_env("stsf_gym/Generated-v0", split="train", camera__enabled=False)
    env.reset(seed=0)
    seeds = {env.unwrapped.world_seed}
    for _ in range(5):
        env.reset()
        seeds.add(env.unwrapped.world_seed)
    assert all(s < 1_000_000 for s in seeds) and len(seeds) > 1


def test_rebuilt_world_runs_like_a_fresh_env(make_env):
    """World A, then B, then A again: the same trajectory as a fresh env on A (the saved
    start state is renewed with the bodies)."""
    env = make_env("stsf_gym/Generated-v0", split="test", **FAST)
    first = drive(env, ACTIONS, seed=1)
    drive(env, ACTIONS, seed=2)
    again = drive(env, ACTIONS, seed=1)
    fresh = drive(make_env("stsf_gym/Generated-v0", split="test", **FAST), ACTIONS, seed=1)
    for run in (again, fresh):
        for (obs_a, info_a), (obs_b, info_b) in zip(first, run, strict=True):
            np.testing.assert_array_equal(info_a["true_pose"], info_b["true_pose"])
            np.testing.assert_array_equal(obs_a["sonar"], obs_b["sonar"])
            np.testing.assert_array_equal(obs_a["landmark_ids"], obs_b["landmark_ids"])


def test_bodies_do_not_pile_up(make_env):
    env = make_env("stsf_gym/Generated-v0", split="test", **FAST)
    env.reset(seed=0)
    client = env.unwrapped.sim.client
    counts = []
    for seed in (1, 0):
        env.reset(seed=seed)
        counts.append(client.getNumBodies())
    world = env.unwrapped.world
    parts = 2 + len(world.walls) + len(world.obstacles) + len(world.boards)  # + floor, robot
    assert counts[-1] == parts


def test_estimator_ids_and_policy_path_follow_the_world(make_env):
    env = make_env("stsf_gym/Generated-Truth-v0", split="test", camera__enabled=False)
    policy = PolicyObservation(env)
    obs, _ = policy.reset(seed=5)
    assert env.unwrapped.world_seed == 1_000_005
    np.testing.assert_allclose(policy.path.points, env.unwrapped.config.world.path)
    policy.reset(seed=6)
    policy.step(policy.action_space.sample())
    np.testing.assert_allclose(policy.path.points, env.unwrapped.config.world.path)
    assert obs.shape == policy.observation_space.shape


@pytest.mark.slow
def test_gymnasium_env_checker(make_env):
    from gymnasium.utils.env_checker import check_env

    check_env(make_env("stsf_gym/Generated-v0", split="test", camera__mode="fast").unwrapped)


def test_world_is_not_an_argument(make_env):
    with pytest.raises(ValueError, match="draws its worlds"):
        make_env("stsf_gym/Generated-v0", world="irl_corridor")


CLI = [sys.executable, "-m", "stsf_gym.cli"]


@pytest.mark.slow
def test_cli_world_yaml_and_grid(tmp_path):
    out = tmp_path / "w.yaml"
    for _ in range(2):  # the second run replaces the file
        result = subprocess.run(
            [*CLI, "world", "--seed", "1000003", "--out", str(out)], capture_output=True, text=True
        )
        assert result.returncode == 0, result.stderr
    assert yaml.safe_load(out.read_text())["name"] == "generated-1000003"
    png = tmp_path / "grid.png"
    result = subprocess.run(
        [*CLI, "world", "--grid", "2", "--out", str(png)], capture_output=True, text=True
    )
    assert result.returncode == 0, result.stderr
    assert png.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.slow
@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--world", "generated"], "needs --split train, val or test"),
        (["--world", "generated", "--split", "dev"], "split must be one of"),
        (["--split", "test"], "--split is for --world generated"),
    ],
)
def test_cli_split_errors(tmp_path, args, message):
    result = subprocess.run(
        [*CLI, "evaluate", *args, "--out", str(tmp_path)], capture_output=True, text=True
    )
    assert result.returncode == 2 and message in result.stderr


@pytest.mark.slow
def test_a_drawn_world_the_generator_cannot_lay_out_is_drawn_again(make_env, monkeypatch):
    """A train world seed of the sparse suite had no layout of its landmark coverage and ended
    a training run (`stsf-gym train --suite sparse`, seed 0, DAgger round 1). A drawn world
    that cannot be generated is replaced by the next draw, the same one on every run; a world
    asked for by seed still raises."""
    reference = make_env("stsf_gym/Generated-v0", split="train", camera__enabled=False)
    reference.reset(seed=0)
    reference.reset()
    unbuildable = reference.unwrapped.world_seed

    def generate(world_seed, *args):
        if world_seed == unbuildable:
            raise GenerationError(f"world seed {world_seed}: no layout")
        return generate_world(world_seed, *args)

    monkeypatch.setattr(generated_env, "generate_world", generate)
    redrawn = []
    for _ in range(2):
        env = make_env("stsf_gym/Generated-v0", split="train", camera__enabled=False)
        env.reset(seed=0)
        env.reset()
        redrawn.append(env.unwrapped.world_seed)
    assert redrawn[0] == redrawn[1] != unbuildable
    with pytest.raises(GenerationError, match=str(unbuildable)):
        env.reset(options={"world_seed": unbuildable})
