"""Config files and the values a user types, each refused in one line before any file is
written: numbers with an exponent (``1e-4``) read as numbers, a ``--set`` key or a level given
twice, config files that are folders, keys written twice, YAML anchors and aliases, and files
over the size bound."""

from __future__ import annotations

import re

import pytest

from stsf_gym.config import parse_overrides
from stsf_gym.config_files import MAX_CONFIG_BYTES, read_yaml
from stsf_gym.validation import ConfigError

# --- numbers a user types -------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "number"),
    [("1e-4", 1e-4), ("1e6", 1e6), ("2E3", 2e3), ("1.5e3", 1.5e3), ("-3e+2", -300.0)],
)
def test_a_number_with_an_exponent_is_a_number(text, number):
    assert parse_overrides([f"finetune.learning_rate={text}"]) == {"finetune.learning_rate": number}


def test_a_finetune_learning_rate_typed_with_an_exponent_is_taken():
    from stsf_gym.agents.training.hyperparams import load_hyperparams

    overrides = parse_overrides(["finetune.learning_rate=1e-4"])
    settings = load_hyperparams("dagger+ppo", None, overrides=overrides, suite=True)
    assert settings.finetune.learning_rate == 1e-4


def test_a_key_set_twice_is_named_before_any_work(run_cli, tmp_path):
    with pytest.raises(ConfigError, match=r"override 'sim.control_dt' is given twice \(0.1, then"):
        parse_overrides(["sim.control_dt=0.1", "camera.width=64", "sim.control_dt=0.2"])
    out = tmp_path / "o"
    code, err = run_cli("evaluate", "--set", "sim.seed=1", "--set", "sim.seed=2", "--out", str(out))
    assert code == 2 and err.strip().endswith("only one could hold: give it once")
    assert not out.exists()


def test_a_level_given_twice_is_named(run_cli, tmp_path):
    code, err = run_cli("accuracy-curve", "--levels", "1,1.0", "--out", str(tmp_path / "o"))
    assert code == 2 and err.strip().endswith("--levels gives the level 1 twice, got '1,1.0'")
    assert not (tmp_path / "o").exists()


# --- config files ---------------------------------------------------------------------------


def write(tmp_path, text: str):
    path = tmp_path / "config.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("text", "said"),
    [
        (
            "sim:\n  max_episode_seconds: 10.0\ncamera: {mode: fast}\nsim:\n  control_dt: 0.1\n",
            "line 4, column 1: key 'sim' is written twice (first at line 1)",
        ),
        ("camera: {mode: fast, mode: gl}\n", "line 1, column 22: key 'mode' is written twice"),
        (
            "a: &a [1, 1, 1, 1, 1, 1, 1, 1]\nb: &b [*a, *a, *a, *a, *a, *a, *a, *a]\nc: [*b, *b]\n",
            "line 1, column 4: config files take no YAML anchors or aliases",
        ),
    ],
)
def test_yaml_a_config_may_not_hold_is_refused_naming_file_and_line(tmp_path, text, said):
    path = write(tmp_path, text)
    with pytest.raises(ConfigError, match=f"^{re.escape(f'{path}: {said}')}"):
        read_yaml(path)


def test_a_config_file_over_the_size_bound_is_refused_unread(tmp_path):
    path = write(tmp_path, "x: [" + "1," * (MAX_CONFIG_BYTES // 2) + "1]\n")
    with pytest.raises(ConfigError, match=rf"config file {path} holds 1\.0 MB, more than"):
        read_yaml(path)


def test_a_folder_as_config_says_it_is_a_folder(run_cli, tmp_path):
    code, err = run_cli("evaluate", "--config", str(tmp_path), "--out", str(tmp_path / "o"))
    assert code == 2 and f"config file {tmp_path} is a folder" in err
    assert not (tmp_path / "o").exists()


def test_an_alias_in_a_set_value_is_refused():
    with pytest.raises(ConfigError, match="override 'sim=\\*x': config files take no YAML"):
        parse_overrides(["sim=*x"])
