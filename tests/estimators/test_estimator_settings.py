"""Estimator settings: frozen, typed and ranged dataclasses whose defaults live in YAML only."""

from __future__ import annotations

import dataclasses
import typing

import pytest
import yaml

from stsf_gym.config_files import CONFIG_DIR
from stsf_gym.estimators import ESTIMATORS, estimator_class, estimator_settings, make_estimator
from stsf_gym.estimators import settings as settings_module
from stsf_gym.validation import ConfigError, Range
from stsf_gym.wrappers import PoseEstimateWrapper


def _yaml(name: str) -> dict:
    return yaml.safe_load((CONFIG_DIR / "estimators" / f"{name}.yaml").read_text())


@pytest.mark.parametrize("name", sorted(ESTIMATORS))
def test_defaults_are_the_yaml_files(name):
    data = _yaml(name)
    while base := data.pop("extends", None):  # stsf.yaml adds its keys to conventional.yaml's
        data = {**_yaml(base), **data}
    assert dataclasses.asdict(estimator_settings(name)) == data
    for field in dataclasses.fields(estimator_class(name).settings_type):
        assert field.default is dataclasses.MISSING, f"{name}.{field.name} has a default in code"


@pytest.mark.parametrize("name", sorted(ESTIMATORS))
def test_every_setting_has_a_type_and_a_range(name):
    hints = typing.get_type_hints(estimator_class(name).settings_type, include_extras=True)
    for field, hint in hints.items():
        ranged = any(isinstance(m, Range) for m in getattr(hint, "__metadata__", ()))
        assert ranged or typing.get_origin(hint) is typing.Literal, f"{name}.{field}"


def test_settings_are_frozen():
    settings = estimator_settings("ekf")
    with pytest.raises(dataclasses.FrozenInstanceError):
        settings.sigma_px = 1.0


def test_keyword_options_override_the_yaml(make_env):
    assert make_estimator("stsf", max_track_frames=4).max_track_frames == 4
    env = PoseEstimateWrapper(make_env(camera__mode="fast"), "stsf", max_track_frames=10)
    assert env.estimator.max_track_frames == 10
    assert env.estimator.settings.weights == "significance"
    made = make_env("stsf_gym/Straight10m-EKF-v0", estimator_options={"max_range": 7.5})
    assert made.unwrapped.config.camera.control == "pan"
    assert made.get_wrapper_attr("estimator").max_range == 7.5


@pytest.mark.parametrize(
    ("name", "options", "message"),
    [
        ("stsf", {"max_track_frames": -1}, r"stsf\.max_track_frames must be >= 1, got -1"),
        ("stsf", {"max_track_frames": 2.5}, r"stsf\.max_track_frames must be an integer"),
        ("stsf", {"weights": "mean"}, r"stsf\.weights must be one of"),
        ("conventional", {"max_track_frames": 3}, r"unknown config key 'conventional\."),
        ("ekf", {"gate_probability": 1.0}, r"ekf\.gate_probability must be in \(0, 1\)"),
        ("ekf", {"min_range": 5.0, "max_range": 2.0}, r"ekf\.max_range must be > min_range"),
        ("ekf", {"relocalise_after": 1}, r"ekf\.relocalise_after must be 0 \(off\)"),
        ("odometry", {"mount_std": -0.1}, r"odometry\.mount_std must be >= 0"),
    ],
)
def test_bad_options_fail_naming_them(name, options, message):
    with pytest.raises(ConfigError, match=message):
        make_estimator(name, **options)


def test_files_extend_and_errors_name_the_file(tmp_path, monkeypatch):
    (tmp_path / "base.yaml").write_text(
        yaml.safe_dump({**_yaml("odometry"), **_yaml("conventional"), "extends": None})
    )
    (tmp_path / "track.yaml").write_text("extends: base\nweights: gls\nmax_track_frames: 0\n")
    (tmp_path / "short.yaml").write_text("extends: base\nweights: gls\n")
    monkeypatch.setattr(settings_module, "ESTIMATOR_DIR", tmp_path)
    STSF = settings_module.STSFSettings
    with pytest.raises(ConfigError, match=r"track\.yaml: track\.max_track_frames must be >= 1"):
        settings_module.load_settings("track", STSF, {})
    loaded = settings_module.load_settings("track", STSF, {"max_track_frames": 3})
    assert (loaded.weights, loaded.max_track_frames, loaded.sigma_px) == ("gls", 3, 0.15)
    with pytest.raises(ConfigError, match=r"missing config key 'short\.max_track_frames'"):
        settings_module.load_settings("short", STSF, {})
