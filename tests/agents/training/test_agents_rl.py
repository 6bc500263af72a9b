"""SB3 agents: the truth pose source, the policy input, hyper-parameter files, and a few
hundred training steps end to end (train, checkpoint, interrupt, resume, load, evaluate).
Smoke tests of the pipeline, not of learning."""

import json
import math
import subprocess
import sys
import warnings
import zipfile

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

from stsf_gym.agents.model_files import model_metadata
from stsf_gym.agents.observation import ObservationConfig, PolicyObservation
from stsf_gym.agents.registry import make_agent
from stsf_gym.agents.training.hyperparams import load_hyperparams
from stsf_gym.agents.training.train import latest_checkpoint, train
from stsf_gym.agents.training.training_log import EpisodeLog, read_rows
from stsf_gym.experiments.evaluate import evaluate
from stsf_gym.validation import ConfigError
from stsf_gym.wrappers import TRUTH_STD, PoseEstimateWrapper

NO_CAMERA = {"camera": {"enabled": False}}
SHORT = {"camera": {"enabled": False}, "sim": {"max_episode_seconds": 3.0}}
TINY_PPO = {
    "n_steps": 64,
    "batch_size": 32,
    "eval_freq": 150,
    "checkpoint_freq": 100,
    "n_eval_episodes": 1,
    "env.sim.max_episode_seconds": 3.0,
}


@pytest.mark.slow
def test_truth_pose_is_the_true_pose_with_a_fixed_tiny_covariance(make_env):
    env = PoseEstimateWrapper(make_env(**NO_CAMERA), "truth")
    obs, info = env.reset(seed=0)
    for _ in range(20):
        np.testing.assert_allclose(obs["pose"], info["true_pose"], atol=1e-6)
        np.testing.assert_allclose(obs["pose_cov"].reshape(3, 3), np.diag(np.square(TRUTH_STD)))
        obs, _, _, _, info = env.step(np.float32([0.8, 0.4]))
    assert info["true_pose"][0] > 0.05  # it moved, and the pose followed
    with pytest.raises(ValueError, match="truth"):
        PoseEstimateWrapper(make_env(**NO_CAMERA), "truth", window=3)


def test_truth_has_a_registered_id(make_env):
    env = make_env("stsf_gym/Corridor-Truth-v0", **NO_CAMERA)
    obs, info = env.reset(seed=1)
    np.testing.assert_allclose(obs["pose"], info["true_pose"], atol=1e-6)


def test_policy_observation_in_the_robot_frame(make_env):
    env = PolicyObservation(PoseEstimateWrapper(make_env(**NO_CAMERA), "truth"))
    scale, lookahead = env.config.scale, np.array(env.config.lookahead)
    k = len(lookahead)
    features, _ = env.reset(seed=0)  # at the path's start, facing along it
    assert features.shape == env.observation_space.shape
    np.testing.assert_allclose(features[0 : 2 * k : 2], lookahead / scale, atol=5e-3)
    np.testing.assert_allclose(features[1 : 2 * k : 2], 0.0, atol=5e-3)
    path_length = env.path.length  # the whole path is left to the only goal, its end
    np.testing.assert_allclose(features[2 * k], path_length / scale, atol=1e-3)
    x, y, yaw = env.unwrapped.start_pose
    goal = env.unwrapped.task.goal - (x, y)
    in_robot = [goal @ (math.cos(yaw), math.sin(yaw)), goal @ (-math.sin(yaw), math.cos(yaw))]
    np.testing.assert_allclose(features[2 * k + 1 : 2 * k + 3], np.array(in_robot) / scale, 1e-5)
    assert features[2 * k + 3] == 1.0  # every goal still to declare
    np.testing.assert_allclose(features[2 * k + 4 : 2 * k + 6], [0.0, 1.0], atol=5e-3)
    np.testing.assert_allclose(features[2 * k + 6 : 2 * k + 9], math.log10(TRUTH_STD[0]) / 3)
    sonar = features[2 * k + 9 : -2]
    assert sonar.shape == (16,) and np.all((sonar >= 0) & (sonar <= 1))
    # facing left, 0.3 m left of the path: the path runs to the robot's right, from behind it
    features, _ = env.reset(seed=0, options={"start_pose": [2.0, 0.3, math.pi / 2]})
    np.testing.assert_allclose(features[0:2], [-0.3 / scale, 0.0], atol=1e-2)
    np.testing.assert_allclose(features[2:4], [-0.3 / scale, -0.5 / scale], atol=1e-2)
    np.testing.assert_allclose(features[2 * k + 4 : 2 * k + 6], [-1.0, 0.0], atol=1e-2)
    assert features[-2:] == pytest.approx([0.0, 0.0])  # standing still


def test_goal_features_saturate_at_the_horizon(make_env):
    """A goal beyond ``goal_horizon`` reads as one at the horizon, in the same direction."""
    far = PolicyObservation(PoseEstimateWrapper(make_env(**NO_CAMERA), "truth"))
    near = PolicyObservation(
        PoseEstimateWrapper(make_env(**NO_CAMERA), "truth"), ObservationConfig(goal_horizon=2.0)
    )
    k, scale = len(far.config.lookahead), far.config.scale
    full, _ = far.reset(seed=0)
    cut, _ = near.reset(seed=0)
    assert full[2 * k] > 2.0 / scale  # the goal is farther than the horizon
    assert cut[2 * k] == pytest.approx(2.0 / scale)
    goal, goal_cut = full[2 * k + 1 : 2 * k + 3], cut[2 * k + 1 : 2 * k + 3]
    np.testing.assert_allclose(goal_cut, goal / np.linalg.norm(goal) * 2.0 / scale, rtol=1e-5)
    np.testing.assert_array_equal(
        np.delete(cut, [2 * k, 2 * k + 1, 2 * k + 2]),
        np.delete(full, [2 * k, 2 * k + 1, 2 * k + 2]),
    )


@pytest.mark.slow
def test_a_far_goal_reads_as_the_route_point_at_the_horizon(make_env):
    """With ``far_goal: route`` a goal beyond the horizon reads as the path's point that far
    ahead (the 2 m lookahead point here); within it, the goal itself, as with ``direction``."""
    k = len(ObservationConfig().lookahead)
    route, direction = (
        PolicyObservation(
            PoseEstimateWrapper(make_env(**NO_CAMERA), "truth"),
            ObservationConfig(goal_horizon=horizon, far_goal=far_goal),
        )
        for horizon, far_goal in ((2.0, "route"), (2.0, "direction"))
    )
    cut, _ = route.reset(seed=0)
    straight, _ = direction.reset(seed=0)
    np.testing.assert_allclose(cut[2 * k + 1 : 2 * k + 3], cut[6:8], atol=1e-6)  # lookahead 2 m
    assert cut[2 * k] == straight[2 * k]
    # the corridor's goal lies off the route's line: the two readings differ
    assert np.abs(cut[2 * k + 1 : 2 * k + 3] - straight[2 * k + 1 : 2 * k + 3]).max() > 0.05
    np.testing.assert_array_equal(
        np.delete(cut, [2 * k + 1, 2 * k + 2]), np.delete(straight, [2 * k + 1, 2 * k + 2])
    )
    near = ObservationConfig(goal_horizon=1000.0, far_goal="route")
    whole = PolicyObservation(PoseEstimateWrapper(make_env(**NO_CAMERA), "truth"), near)
    unbounded = PolicyObservation(PoseEstimateWrapper(make_env(**NO_CAMERA), "truth"))
    np.testing.assert_array_equal(whole.reset(seed=0)[0], unbounded.reset(seed=0)[0])


def _write(tmp_path, text: str):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    return path


GOOD = (
    "default: {n_envs: 1, n_timesteps: 10, policy: MlpPolicy, eval_freq: 5, "
    "n_eval_episodes: 1, checkpoint_freq: 5"
)


@pytest.mark.parametrize(
    ("extra", "named"),
    [
        (", learnin_rate: 0.1}", r"bad\.yaml.*'learnin_rate'.*did you mean 'learning_rate'"),
        (", n_steps: many}", r"bad\.yaml.*n_steps must be like 2048, got 'many'"),
        (", gamma: true}", r"bad\.yaml.*gamma"),
        (", policy_kwargs: {activation_fn: swish}}", r"bad\.yaml.*activation_fn.*'swish'"),
        ("}\nstsf_gym/Corridor-Truht-v0: {n_envs: 2}", r"bad\.yaml.*'stsf_gym/Corridor-Truht-v0'"),
        ("}\nstsf_gym/Corridor-Truth-v0: {n_envs: two}", r"bad\.yaml.*n_envs must be a number"),
        ("}\nstsf_gym/Corridor-Truth-v0: {env: 3}", r"bad\.yaml.*env must be a mapping"),
    ],
)
def test_bad_hyperparameter_files_name_the_file_and_key(tmp_path, extra, named):
    path = _write(tmp_path, GOOD + extra)
    with pytest.raises(ConfigError, match=named):
        load_hyperparams("ppo", "stsf_gym/Corridor-Truth-v0", path)


def test_hyperparameter_sections_and_overrides_merge(tmp_path):
    path = _write(tmp_path, GOOD + ", gamma: 0.9}\nstsf_gym/Corridor-Truth-v0: {n_envs: 3}")
    hp = load_hyperparams("ppo", "stsf_gym/Corridor-Truth-v0", path, {"env.sim.control_dt": 0.2})
    assert hp.section == "stsf_gym/Corridor-Truth-v0" and hp.training.n_envs == 3
    assert hp.algo_kwargs == {"gamma": 0.9}
    assert hp.training.env == {"sim": {"control_dt": 0.2}}
    assert load_hyperparams("ppo", "stsf_gym/Corridor-STSF-v0", path).training.n_envs == 1
    for algo in ("ppo", "sac"):  # the shipped files are valid for every pose source
        for source in ("Truth", "Odometry", "Conventional", "STSF", "EKF"):
            load_hyperparams(algo, f"stsf_gym/Corridor-{source}-v0")


@pytest.mark.slow
def test_train_cli_names_the_bad_key(tmp_path):
    path = _write(tmp_path, GOOD + ", clip_rnge: 0.1}")
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "stsf_gym.cli",
            "train",
            "--config",
            str(path),
            "--out",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 2
    assert "'clip_rnge'" in result.stderr and "bad.yaml" in result.stderr


@pytest.mark.slow
def test_ppo_trains_saves_loads_and_evaluates(tmp_path):
    out = tmp_path / "ppo"
    summary = train(
        "ppo", "truth", out, 320, seed=3, n_envs=1, overrides=TINY_PPO, progress_bar=False
    )
    assert summary["timesteps"] == 320 and summary["resumed_from"] == 0
    for name in ("model.zip", "train.json", "learning_curve.png", "best/best_model.zip"):
        assert (out / name).stat().st_size > 0
    assert json.loads((out / "train.json").read_text())["timesteps"] == summary["timesteps"]
    # a checkpoint after every update; kept where a multiple of checkpoint_freq (100) was passed
    kept = sorted(int(p.stem.split("_")[1]) for p in (out / "checkpoints").glob("model_*.zip"))
    assert kept == [128, 256, 320]
    assert any((out / "tb").iterdir())
    episodes = read_rows(out / "episodes.csv")
    assert len(episodes) >= 320 // 30 - 1 and np.all(episodes[:, 2] <= 30)  # 3 s episodes
    assert summary["last_evaluation"]["timesteps"] == 300
    meta = model_metadata(out / "model.zip")
    assert meta["estimator"] == "truth" and meta["wall_time_s"] > 0
    # evaluated like the follower, on another pose source than it was trained on
    result, by_estimator = evaluate(
        tmp_path / "eval", ["odometry"], 1, agent=str(out / "model.zip"), workers=1, env=SHORT
    )
    assert result["trained"]["estimator"] == "truth" and result["trained"]["algo"] == "ppo"
    (episode,) = by_estimator["odometry"]
    assert episode.outcome in ("time", "collision") and 0 < episode.steps <= 30
    assert episode.distance > 0


def test_loaded_agent_acts_deterministically(tmp_path, make_env):
    out = tmp_path / "sac"
    sac = {**TINY_PPO, "learning_starts": 50, "buffer_size": 1000, "batch_size": 32}
    del sac["n_steps"]
    summary = train("sac", "odometry", out, 150, n_envs=1, overrides=sac, progress_bar=False)
    assert summary["timesteps"] == 150
    assert latest_checkpoint(out)[1] == 150
    assert list((out / "checkpoints").glob("model_replay_buffer_*_steps.pkl"))
    env = PoseEstimateWrapper(make_env(**NO_CAMERA), "odometry")
    agent = make_agent(str(out / "model.zip"))
    obs, _ = agent.wrap(env).reset(seed=0)
    action = agent.act(obs)
    assert action.shape == (2,) and np.all(np.abs(action) <= 1)
    np.testing.assert_array_equal(agent.act(obs), action)
    with pytest.raises(ConfigError, match="not found"):
        make_agent(str(tmp_path / "missing.zip"))


def test_timesteps_must_be_whole_updates_and_nothing_is_written_otherwise(tmp_path):
    out = tmp_path / "run"
    message = "timesteps 300 is not a multiple of n_steps x n_envs = 64: the run would end at 320"
    with pytest.raises(ConfigError, match=message + "; ask for 256 or 320"):
        train("ppo", "truth", out, 300, n_envs=1, overrides=TINY_PPO, progress_bar=False)
    sac = {**TINY_PPO, "train_freq": 4}
    del sac["n_steps"]
    with pytest.raises(ConfigError, match="train_freq x n_envs = 4: the run would end at 304"):
        train("sac", "truth", out, 301, n_envs=1, overrides=sac, progress_bar=False)
    assert not out.exists()


def test_interrupt_saves_a_checkpoint_and_a_rerun_resumes(tmp_path, monkeypatch):
    out = tmp_path / "run"
    original = EpisodeLog._on_step

    def interrupt_at_100(self):
        original(self)
        if self.num_timesteps >= 100:
            raise KeyboardInterrupt
        return True

    monkeypatch.setattr(EpisodeLog, "_on_step", interrupt_at_100)
    with pytest.raises(KeyboardInterrupt):
        train("ppo", "truth", out, 320, n_envs=1, overrides=TINY_PPO, progress_bar=False)
    # PPO's latest update (after the first 64-step rollout) is the checkpoint, not step 100
    assert latest_checkpoint(out)[1] == 64 and not (out / "model.zip").exists()
    monkeypatch.setattr(EpisodeLog, "_on_step", original)
    summary = train("ppo", "truth", out, 320, n_envs=1, overrides=TINY_PPO, progress_bar=False)
    assert summary["resumed_from"] == 64 and summary["timesteps"] == 320
    for saved in (latest_checkpoint(out)[0], out / "model.zip"):  # no path of this machine
        with zipfile.ZipFile(saved) as archive:
            assert "tensorboard_log" not in json.loads(archive.read("data"))
    assert any((out / "tb").iterdir())  # the resumed run logged under its own folder again
    steps = read_rows(out / "episodes.csv")[:, 0]
    assert np.all(np.diff(steps) > 0)  # no episode logged twice across the resume
    with pytest.raises(ConfigError, match="estimator 'truth'"):
        train("ppo", "odometry", out, 384, n_envs=1, overrides=TINY_PPO, progress_bar=False)


def test_policy_env_passes_both_checkers(make_env):
    env = PolicyObservation(make_env("stsf_gym/Corridor-Truth-v0", **NO_CAMERA))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.filterwarnings("ignore", message=".*different from the unwrapped version")
        gym_check_env(env)
        sb3_check_env(env, warn=True)


def test_an_interrupted_save_keeps_the_previous_model(tmp_path):
    from stsf_gym.agents.training.train import save_atomic

    path = tmp_path / "model.zip"
    save_atomic(lambda f: f.write(b"first"), path)

    def interrupted(f):
        f.write(b"half")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        save_atomic(interrupted, path)
    assert path.read_bytes() == b"first"
    assert [p.name for p in tmp_path.iterdir()] == ["model.zip"]
