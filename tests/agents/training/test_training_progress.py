"""A training run shows its progress: a bar per stage drawn before the stage's work starts,
TensorBoard scalars for the demonstration rounds, and a learning curve drawn from the run's
own records (val success and return against env steps and wall time)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from stsf_gym.agents.training import train as train_module
from stsf_gym.agents.training.progress import RewardProgress, stage_bar
from stsf_gym.agents.training.train import train
from stsf_gym.agents.training.training_log import curve_points

TINY = {
    "demonstrations.expert_episodes": 1,
    "demonstrations.rounds": 1,
    "demonstrations.episodes_per_round": 1,
    "demonstrations.cloning.epochs": 2,
    "n_eval_episodes": 1,
    "env.sim.max_episode_seconds": 5.0,
    "train_env.sim.max_episode_seconds": 5.0,
    "train_env.task.leg_min": 1.0,
    "train_env.task.leg_max": 1.5,
}


def test_bars_tensorboard_and_the_learning_curve_of_the_demonstration_stage(
    tmp_path, capfd, monkeypatch
):
    drawn_before_the_envs = []
    make = train_module.make_vec_env

    def noting(*args, **kwargs):
        drawn_before_the_envs.append("demonstrations (episodes)" in capfd.readouterr().err)
        return make(*args, **kwargs)

    monkeypatch.setattr(train_module, "make_vec_env", noting)
    out = tmp_path / "run"
    summary = train("dagger", "truth", out, n_envs=1, overrides=TINY, suite="corridor")
    assert summary["algo"] == "dagger" and drawn_before_the_envs[0]
    err = capfd.readouterr().err
    assert "2/2" in err and ("ep/s" in err or "s/ep" in err)  # the count, with a rate (and ETA)
    points = curve_points(out)
    assert [p["stage"] for p in points] == ["demonstrations", "demonstrations"]
    assert all(len(p["val_returns"]) == 1 and p["control_steps"] > 0 for p in points)
    assert points[1]["control_steps"] > points[0]["control_steps"]
    assert list((out / "tb" / "demonstrations").glob("events.out.tfevents.*"))
    assert (out / "learning_curve.png").stat().st_size > 0


def test_the_reward_stage_shows_a_bar_and_logs_its_evaluations(tmp_path, capfd):
    plain = {
        "n_steps": 32, "batch_size": 32, "n_epochs": 1, "eval_freq": 32, "n_eval_episodes": 1,
        "env.sim.max_episode_seconds": 3.0, "env.camera.enabled": False,
    }  # fmt: skip
    out = tmp_path / "plain"
    train("ppo", "truth", out, 64, n_envs=1, overrides=plain)
    assert "learning from reward (ppo, decisions)" in capfd.readouterr().err
    points = curve_points(out)
    assert [p["stage"] for p in points] == ["reward", "reward"]
    assert points[1]["wall_time_s"] > points[0]["wall_time_s"] > 0


def test_a_resumed_reward_stage_rates_only_the_decisions_run_in_this_process():
    clock = [1_000.0]
    bar = stage_bar("learning from reward", 1_638_400, "decision", True, initial=88_064)
    bar._time = lambda: clock[0]
    model = SimpleNamespace(num_timesteps=88_064, get_env=lambda: None, logger=None)
    progress = RewardProgress(bar)
    progress.init_callback(model)
    progress.on_training_start({}, {})
    assert (bar.initial, bar.n, bar.format_dict["elapsed"]) == (88_064, 88_064, 0)
    clock[0] += 10.0
    model.num_timesteps += 1_000  # 100 decisions/s here, not 89,064 in 10 s
    progress.on_step()
    meter = bar.format_dict
    assert meter["n"] == 89_064 and meter["rate"] == pytest.approx(100.0)
    assert "100.00decision/s" in bar.format_meter(**meter)
    bar.close()
