import gymnasium as gym
import pytest
import yaml

from envs.config import ConfigError, load_config


def test_defaults_and_world_layers():
    cfg = load_config()
    assert cfg.world.name == "irl_corridor"
    assert cfg.camera.width == 320 and cfg.camera.rate_hz == 5.0
    assert cfg.robot.nominal_speed == pytest.approx(0.122)
    assert load_config(world="straight_10m").world.name == "straight_10m"
    cluttered = load_config(world="irl_corridor_cluttered")
    assert cluttered.world.walls == cfg.world.walls and len(cluttered.world.obstacles) == 4


def test_overrides_in_all_forms(tmp_path):
    assert load_config(camera__width=640).camera.width == 640
    assert load_config(**{"camera.width": 640}).camera.width == 640
    assert load_config(camera={"rate_hz": 10}).camera.rate_hz == 10.0
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump({"sonar": {"max_range": 3.0}, "world": "straight_10m"}))
    cfg = load_config(path, sonar__count=8)
    assert (cfg.sonar.max_range, cfg.sonar.count, cfg.world.name) == (3.0, 8, "straight_10m")
    assert load_config({"world": {"goal_radius": 1.0}}).world.goal_radius == 1.0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"camera__widht": 640}, "camera.widht"),
        ({"cmaera": {"width": 640}}, "'cmaera'"),
        ({"world": {"landmarks": [{"id": 1, "at": [0, 0], "facing": 0}]}}, "landmarks[0].facing"),
        ({"camera__width": "big"}, "camera.width"),
        ({"camera__renderer": "vulkan"}, "camera.renderer"),
        ({"sonar__count": 2.5}, "sonar.count"),
        ({"world": "atlantis"}, "atlantis"),
    ],
)
def test_bad_config_is_named(kwargs, message):
    config = kwargs.pop("world", None)
    with pytest.raises(ConfigError, match=message.replace("[", r"\[").replace("]", r"\]")):
        if isinstance(config, dict):
            load_config({"world": config}, **kwargs)
        else:
            load_config(world=config, **kwargs)


def test_make_rejects_unknown_key_and_missing_file():
    with pytest.raises(ConfigError, match=r"sonar\.rays"):
        gym.make("stsf_gym/Corridor-v0", sonar__rays=3)
    with pytest.raises(ConfigError, match="not found"):
        gym.make("stsf_gym/Corridor-v0", config="no/such/file.yaml")


def test_make_with_config_file(tmp_path, make_env):
    path = tmp_path / "cfg.yaml"
    path.write_text(yaml.safe_dump({"camera": {"width": 160, "height": 120}}))
    env = make_env(config=str(path))
    assert env.observation_space["image"].shape == (120, 160, 3)
    assert env.unwrapped.camera_matrix[0, 2] == pytest.approx(79.5)
