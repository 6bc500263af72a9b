"""A training campaign (``stsf-gym train --estimators``) on Ray trains what it trains locally:
the same runs in the same folders, the same policies to the bit."""

from __future__ import annotations

import zipfile

import pytest

from stsf_gym.experiments.campaign import campaign_jobs, run_campaign

#: The learner on the corridor suite, tiny: one expert leg, no DAgger round, 1 val route.
TINY = {
    "algo": "ppo",
    "timesteps": None,
    "world": "irl_corridor",
    "config": None,
    "overrides": {
        "demonstrations.expert_episodes": 1,
        "demonstrations.rounds": 0,
        "n_eval_episodes": 1,
        "env.sim.max_episode_seconds": 10,
        "train_env.sim.max_episode_seconds": 8,
    },
    "n_envs": 1,
    "suite": "corridor",
}


def _policy(folder) -> bytes:
    with zipfile.ZipFile(folder / "model.zip") as model:
        return model.read("policy.pth")


@pytest.mark.slow
def test_a_campaign_on_ray_trains_what_it_trains_locally(tmp_path):
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install 'stsf-gym[ray]')")
    local = run_campaign(campaign_jobs(TINY, tmp_path / "local", ["truth"], [0]))
    jobs = campaign_jobs(TINY, tmp_path / "ray", ["truth", "odometry"], [0])
    finished = []
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        on_ray = run_campaign(jobs, backend="ray", on_done=lambda job, _: finished.append(job))
    finally:
        ray.shutdown()
    assert [run["estimator"] for run in on_ray] == ["truth", "odometry"]
    assert sorted(job["estimator"] for job in finished) == ["odometry", "truth"]
    for run in ("truth", "odometry"):
        assert (tmp_path / "ray" / run / "seed-0" / "train.json").is_file()
    assert on_ray[0]["made_by"] == local[0]["made_by"]
    assert on_ray[0]["demonstrations"]["val_success"] == local[0]["demonstrations"]["val_success"]
    assert _policy(tmp_path / "ray" / "truth" / "seed-0") == _policy(
        tmp_path / "local" / "truth" / "seed-0"
    )
