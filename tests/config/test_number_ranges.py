"""Every number has a physical or mathematical range, checked where it enters: configs and
world YAML, hyper-parameters, and what a pose source returns each step (a log's sensor model:
tests/recording/test_outside_logs.py)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from stsf_gym.agents.training.hyperparams import load_hyperparams
from stsf_gym.envs.config import load_config
from stsf_gym.estimators.base import PoseEstimator
from stsf_gym.validation import ConfigError, Positive, Range, build, check_number
from stsf_gym.wrappers import EstimateError, PoseEstimateWrapper, check_estimate

CORRIDOR_ID = "stsf_gym/Corridor-Truth-v0"

# --- configs and worlds -------------------------------------------------------------------


@pytest.mark.parametrize(
    ("config", "message"),
    [
        ({"world": {"wall_height": 1e300}}, r"world\.wall_height must be in \(0, 10000\]"),
        ({"robot": {"wheel_radius": 1e308}}, r"robot\.wheel_radius must be in \(0, 10\]"),
        ({"robot": {"camera_height": 40.0}}, r"robot\.camera_height must be in \(0, 10\]"),
        ({"world": {"start": [2e4, 0.0, 0.0]}}, r"world\.start\[0\] must be in \[-10000, 10000\]"),
        ({"sonar": {"noise_std": 1e300}}, r"sonar\.noise_std must be within ±1e\+09"),
        ({"sim": {"max_episode_seconds": float("nan")}}, "must be a finite number"),
    ],
)
def test_values_physics_forbids_are_refused(config, message):
    with pytest.raises(ConfigError, match=message):
        load_config(config, world="straight_10m")


def _landmarks(*extra: dict) -> dict:
    board = {"id": 1, "at": [2.5, 1.2], "facing_deg": -90}
    return {"world": {"landmarks": [board, *extra]}}


def test_boards_overlapping_on_a_wall_are_refused():
    with pytest.raises(ConfigError, match=r"landmarks\[1\]\.at overlaps landmarks\[0\]"):
        load_config(
            _landmarks({"id": 2, "at": [2.8, 1.2], "facing_deg": -90}), world="straight_10m"
        )


def test_boards_a_board_width_apart_or_on_other_walls_are_accepted():
    size = load_config(world="straight_10m").world.landmark_pattern.size
    apart = {"id": 2, "at": [2.5 + size, 1.2], "facing_deg": -90}
    across = {"id": 3, "at": [2.5, -1.2], "facing_deg": 90}  # the opposite wall
    world = load_config(_landmarks(apart, across), world="straight_10m").world
    assert [lm.id for lm in world.landmarks] == [1, 2, 3]


def test_an_empty_world_file_is_named(tmp_path):
    empty = tmp_path / "empty_world.yaml"
    empty.write_text("")
    with pytest.raises(ConfigError, match=rf"^{empty}: missing config key 'world\.name'"):
        load_config(world=str(empty))


def test_check_number_is_the_configs_check():
    assert check_number(3, "k", Range(gt=0), integer=True) == 3
    assert isinstance(check_number(2, "k"), float)
    for value, message in [
        (float("inf"), "k must be a finite number"),
        (1e10, "k must be within"),
        (2.5, "k must be an integer"),
        (True, "k must be a number"),
        (0, r"k must be > 0"),
    ]:
        with pytest.raises(ConfigError, match=message):
            check_number(value, "k", Range(gt=0), integer=value == 2.5)


# --- hyper-parameters ---------------------------------------------------------------------


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"gamma": 1.5}, r"^--set: gamma must be in \[0, 1\], got 1\.5"),
        ({"learning_rate": -0.001}, r"^--set: learning_rate must be > 0, got -0\.001"),
        ({"learning_rate": float("nan")}, r"^--set: learning_rate must be a finite number"),
        ({"n_stepz": 64}, r"^--set: unknown hyper-parameter 'n_stepz'.*did you mean 'n_steps'"),
        ({"batch_size": 1}, r"^--set: batch_size must be >= 2"),
        ({"n_envs": 0}, r"^--set: n_envs must be >= 1, got 0"),
        ({"clip_range": 0}, r"^--set: clip_range must be > 0"),
    ],
)
def test_bad_hyperparameters_blame_set_not_the_packages_file(overrides, message):
    with pytest.raises(ConfigError, match=message):
        load_hyperparams("ppo", CORRIDOR_ID, overrides=overrides)


def test_a_bad_hyperparameter_in_a_file_names_the_file_and_its_section(tmp_path):
    path = tmp_path / "ppo.yaml"
    path.write_text(
        "default: {n_envs: 1, n_timesteps: 10, policy: MlpPolicy, eval_freq: 5, "
        "n_eval_episodes: 1, checkpoint_freq: 5}\n"
        f"{CORRIDOR_ID}: {{gae_lambda: 1.2}}\n"
    )
    with pytest.raises(ConfigError, match=rf"{path} \[{CORRIDOR_ID}\]: gae_lambda must be in"):
        load_hyperparams("ppo", CORRIDOR_ID, path)
    with pytest.raises(ConfigError, match=r"^--set: tau must be in \(0, 1\]"):
        load_hyperparams("sac", CORRIDOR_ID, overrides={"tau": 2})


def test_train_with_a_bad_set_exits_2_before_writing(run_cli, tmp_path):
    out = tmp_path / "out"
    code, err = run_cli("train", "--set", "gamma=1.5", "--out", str(out))
    assert code == 2 and "--set: gamma must be in [0, 1], got 1.5" in err
    assert not out.exists()


# --- what a pose source returns -----------------------------------------------------------


GOOD_COV = np.diag([0.01, 0.02, 0.003])


@pytest.mark.parametrize(
    ("mean", "cov", "message"),
    [
        ([np.nan, 0.0, 0.0], GOOD_COV, "pose .* not three finite numbers"),
        ([0.0, 0.0], GOOD_COV, "pose .* not three finite numbers"),
        ([0.0, 0.0, 0.0], np.eye(2), "not a finite 3x3 matrix"),
        ([0.0, 0.0, 0.0], np.full((3, 3), np.inf), "not a finite 3x3 matrix"),
        ([0.0, 0.0, 0.0], [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]], "not symmetric"),
        ([0.0, 0.0, 0.0], -GOOD_COV, "not positive definite"),
        ([0.0, 0.0, 0.0], [[1, 2, 0], [2, 1, 0], [0, 0, 1]], "not positive definite"),
        ([0.0, 0.0, 0.0], np.zeros((3, 3)), "not positive definite"),
    ],
)
def test_an_estimate_that_is_no_estimate_is_refused_naming_the_source(mean, cov, message):
    with pytest.raises(EstimateError, match=f"pose source 'mine' returned .*{message}"):
        check_estimate("mine", mean, cov)


def test_a_valid_estimate_passes_with_rounding_asymmetry():
    cov = GOOD_COV + np.array([[0, 1e-12, 0], [0, 0, 0], [0, 0, 0]])
    mean, checked = check_estimate("mine", [1.0, 2.0, 7.0], cov)  # yaw need not be wrapped
    assert mean.tolist() == [1.0, 2.0, 7.0] and np.array_equal(checked, cov)


def test_the_positive_definiteness_check_agrees_with_numpys_cholesky():
    rng = np.random.default_rng(0)
    for _ in range(2000):
        root = rng.normal(size=(3, 3))
        cov = root @ root.T - rng.uniform(0, 2) * np.eye(3)  # about half are not definite
        try:
            np.linalg.cholesky(cov)
            definite = True
        except np.linalg.LinAlgError:
            definite = False
        try:
            check_estimate("mine", [0.0, 0.0, 0.0], cov)
            passed = True
        except EstimateError:
            passed = False
        assert passed == definite, cov


@dataclass(frozen=True)
class NoSettings:
    """A user's estimator without options."""


class NaNAfterTwoSteps(PoseEstimator):
    """A user's estimator that goes wrong on its third step."""

    settings_type: ClassVar[type] = NoSettings

    def __init__(self, settings: NoSettings) -> None:
        super().__init__()
        self.steps = 0

    def update(self, obs: dict, dt: float) -> tuple[np.ndarray, np.ndarray]:
        self.steps += 1
        return (self.mean if self.steps < 3 else np.full(3, np.nan)), self.cov


def test_the_wrapper_blames_the_estimator_not_the_action(make_env):
    name = f"{__name__}:NaNAfterTwoSteps"  # a user's package.module:Class
    corridor = make_env("stsf_gym/Straight10m-v0", camera__enabled=False)
    env = PoseEstimateWrapper(corridor, name)
    env.reset(seed=0)
    for _ in range(2):
        env.step(np.zeros(2, np.float32))
    with pytest.raises(EstimateError, match=f"pose source '{name}' returned the pose"):
        env.step(np.zeros(2, np.float32))


# --- settings typed as a union ---------------------------------------------------------------


@dataclass(frozen=True)
class OptionalLimit:
    """A setting typed ``X | None``: each member of the union is checked."""

    limit: Positive | None = None


def test_a_union_typed_setting_checks_each_member():
    assert build(OptionalLimit, {"limit": None}, "x").limit is None
    assert build(OptionalLimit, {"limit": 2}, "x").limit == 2.0
    with pytest.raises(ConfigError, match=r"x\.limit must be a number, got True"):
        build(OptionalLimit, {"limit": True}, "x")
    with pytest.raises(ConfigError, match=r"x\.limit must be > 0, got -1"):
        build(OptionalLimit, {"limit": -1}, "x")
