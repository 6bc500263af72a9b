"""Every ``info`` key keeps its shape and type through an episode, so a recorder stores it
(Minari's ``DataCollector(record_infos=True)`` compares each step's info with the reset's)."""

from __future__ import annotations

import numpy as np
import pytest

SUITE_ID = "stsf_gym/Suite-Sparse-Truth-v0"  # seed 0: a route of three goals
STOP, DRIVE = [0.0, 0.0, 1.0], [0.5, 0.0, -1.0]


def layout(info: dict) -> dict:
    """Each key of ``info`` (nested mappings by their path) as (type, shape, dtype)."""
    out = {}
    for key, value in info.items():
        if isinstance(value, dict):
            out.update({f"{key}.{k}": v for k, v in layout(value).items()})
        else:
            out[key] = (type(value), np.shape(value), getattr(value, "dtype", None))
    return out


def stopping_episode(env) -> list[dict]:
    """The reset's and every step's info of ``env`` (:data:`SUITE_ID`): a stop at the first
    goal (reached), a drive, then a stop off the second goal (the episode ends)."""
    obs, _ = env.reset(seed=0)
    goal = [float(v) for v in obs["goal"]]
    _, info = env.reset(seed=0, options={"start_pose": [*goal, 0.0]})
    infos = [info]
    for action in [STOP, DRIVE, DRIVE, STOP]:
        *_, terminated, truncated, info = env.step(np.array(action, np.float32))
        infos.append(info)
        if terminated or truncated:
            break
    return infos


def test_every_info_key_keeps_its_shape_and_type_through_an_episode(make_env):
    infos = stopping_episode(make_env(SUITE_ID))
    assert [i["stops"] for i in infos] == [0, 1, 1, 1, 2]
    assert [i["last_stop"]["success"] for i in infos] == [False, True, True, True, False]
    assert infos[0]["last_stop"]["goal"] == -1 and infos[-1]["last_stop"]["goal"] == 1
    first = layout(infos[0])
    for step, info in enumerate(infos[1:], 1):
        assert layout(info) == first, f"step {step}"
    assert not any(t in (list, tuple) for t, _, _ in first.values())


@pytest.mark.parametrize("env_id", ["stsf_gym/RL-Sparse-Truth-v0", "stsf_gym/RL-Sparse-STSF-v0"])
def test_the_rl_ready_ids_infos_keep_theirs_and_monitor_reads_is_success(make_env, env_id):
    from stable_baselines3.common.monitor import Monitor

    leg = make_env(env_id, sim__max_episode_seconds=5.0)  # a leg of 10 decisions
    env = Monitor(leg, info_keywords=("is_success",))
    _, info = env.reset(seed=0)
    infos = [info]
    while not infos[-1].get("episode"):
        infos.append(env.step(np.array(DRIVE, np.float32))[-1])
    first = layout(infos[0])
    assert "is_success" in first and "control_steps" in first
    for step, info in enumerate(infos[1:], 1):
        mine = {k: v for k, v in info.items() if k != "episode"}  # Monitor's, at the end
        assert layout(mine) == first, f"step {step}"
    assert [i["is_success"] for i in infos] == [False] * len(infos)
    assert infos[-1]["episode"]["is_success"] is False and len(infos) == 11


@pytest.mark.slow
def test_minari_records_a_suite_episode_with_its_infos(tmp_path, monkeypatch):
    """Needs ``minari[create]`` (jax, jaxlib: about 380 MB installed, not in the dev extra)."""
    pytest.importorskip("jax")
    minari = pytest.importorskip("minari")
    import gymnasium as gym

    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path))
    env = minari.DataCollector(gym.make(SUITE_ID), record_infos=True)
    steps = len(stopping_episode(env))
    dataset = env.create_dataset("stsf/suite-sparse-truth-v0")
    episode = next(dataset.iterate_episodes())
    env.close()
    assert episode.infos["stops"].tolist() == [0, 1, 1, 1, 2][:steps]
    assert episode.infos["last_stop"]["position"].shape == (steps, 2)
