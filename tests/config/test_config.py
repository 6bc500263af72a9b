import dataclasses
import re
import typing

import gymnasium as gym
import pytest
import yaml

from stsf_gym.envs.config import CONFIG_DIR, EnvConfig, load_config
from stsf_gym.validation import ConfigError


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


# --- ranges, geometry and file names in errors -----------------------------------------------

IRL_LANDMARK_1 = {"id": 1, "at": [3.0, 0.8], "facing_deg": -90}


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"robot__wheel_radius": -0.1}, "robot.wheel_radius must be in (0, 10], got -0.1"),
        ({"encoders__ticks_per_rev": 0}, "encoders.ticks_per_rev must be >= 1, got 0"),
        ({"camera__width": 0}, "camera.width must be in [1, 8192], got 0"),
        ({"render__height": 10_000}, "render.height must be in [1, 8192], got 10000"),
        ({"sonar__dropout_prob": 1.5}, "sonar.dropout_prob must be in [0, 1], got 1.5"),
        ({"camera__vfov_deg": 180}, "camera.vfov_deg must be in (0, 180), got 180.0"),
        (
            {"camera__sensor__read_noise": float("nan")},
            "camera.sensor.read_noise must be a finite number",
        ),
        ({"encoders__radius_error_std": 1.0}, "encoders.radius_error_std must be in [0, 1)"),
        ({"camera__fast__max_detections": 0}, "camera.fast.max_detections must be >= 1"),
        ({"camera__near": 5.0, "camera__far": 4.0}, "camera.far must be > near (5.0), got 4.0"),
        ({"sonar__min_range": 6.0}, "sonar.max_range must be > min_range (6.0)"),
        ({"sim__control_dt": 0.11}, "sim.control_dt must be a whole number of physics steps"),
        (  # the camera would silently run at 1/control_dt
            {"sim__control_dt": 0.3},
            "sim.control_dt must be <= 1/camera.rate_hz (0.2 s: one frame per step at most), "
            "got 0.3",
        ),
        ({"camera__rate_hz": 20.0}, "sim.control_dt must be <= 1/camera.rate_hz (0.05 s"),
        ({"robot__nominal_speed": 1.0}, "robot.nominal_speed must be <= max_speed (0.25)"),
        ({"camera__pan_deg": 200}, "camera.pan_deg must be within robot.pan_limit_deg (±170)"),
        ({"robot__tilt_limit_deg": 95}, "robot.tilt_limit_deg must be in [0, 90], got 95.0"),
    ],
)
def test_impossible_values_name_key_range_and_value(overrides, message):
    with pytest.raises(ConfigError, match=re.escape(message)):
        load_config(**overrides)


@pytest.mark.parametrize(
    ("world", "message"),
    [
        ({"landmarks": [{**IRL_LANDMARK_1, "at": [3.0, 0.5]}]}, "landmarks[0].at must lie on a"),
        ({"landmarks": [{**IRL_LANDMARK_1, "facing_deg": 0}]}, "landmarks[0].facing_deg must"),
        (
            {"landmarks": [IRL_LANDMARK_1, IRL_LANDMARK_1]},
            "landmarks[1].id must be unique, got 1 again",
        ),
        ({"landmarks": [{**IRL_LANDMARK_1, "id": 256}]}, "landmarks[0].id must be in [0, 255]"),
        ({"landmark_height": 1.9}, "world.landmark_height must be in [0.275, 1.725]"),
        ({"start": [0.0, 0.7, 0.0]}, "world.start must be at least robot.body_radius"),
        ({"start": [40.0, 0.0, 0.0]}, "world.start must be inside the walls' bounds"),
        ({"path": [[0.0, 0.0], [3.0, 0.7]]}, "world.path[1] must be at least robot.body_radius"),
        ({"path": [[0.0, 0.0]]}, "world.path must have at least 2 points, got 1"),
        ({"walls": [[0, 0, 0, 0]]}, "world.walls[0] must join two different points"),
        ({"wall_thickness": 0}, "world.wall_thickness must be in (0, 10000], got 0"),
        (
            {"obstacles": [{"shape": "cylinder", "position": [0.3, 0.0], "size": [0.2, 1.0]}]},
            "world.start must be at least robot.body_radius (0.25 m) from every obstacle",
        ),
        (
            {"obstacles": [{"shape": "box", "position": [5.0, 0.0], "size": [0.2, 1.0]}]},
            "world.obstacles[0].size of a box must have 3 entries",
        ),
    ],
)
def test_impossible_world_geometry_is_named(world, message):
    with pytest.raises(ConfigError, match=re.escape(message)):
        load_config(world=world)


def test_every_shipped_world_passes_the_checks():
    for path in sorted((CONFIG_DIR / "worlds").glob("*.yaml")):
        assert load_config(world=path.stem).world.name == path.stem


def test_errors_name_the_file_that_set_the_key(tmp_path):
    config = tmp_path / "robot.yaml"
    config.write_text("robot:\n  wheel_radius: -0.1\n")
    with pytest.raises(ConfigError) as err:
        load_config(config)
    assert str(err.value) == f"{config}: robot.wheel_radius must be in (0, 10], got -0.1"
    assert err.value.key == "robot.wheel_radius" and err.value.source == str(config)

    world = tmp_path / "world.yaml"  # extends a shipped world, breaks one of its landmarks
    world.write_text(
        "extends: irl_corridor\nname: w\nlandmarks: [{id: 1, at: [3, 0.5], facing_deg: -90}]\n"
    )
    with pytest.raises(ConfigError, match=rf"^{re.escape(str(world))}: world\.landmarks\[0\]\.at"):
        load_config(world=str(world))
    # a key the user did not touch is blamed on the file that did set it
    with pytest.raises(ConfigError, match=r"^configs/worlds/irl_corridor\.yaml: world\.start"):
        load_config(world={"wall_thickness": 1.2})
    # a keyword override names no file
    with pytest.raises(ConfigError, match=r"^sonar\.count must be >= 1"):
        load_config(config, robot__wheel_radius=0.1, sonar__count=0)


def test_malformed_yaml_names_file_and_line(tmp_path):
    path = tmp_path / "broken.yaml"
    path.write_text("camera:\n  width: 320\n   height: 240\n")
    with pytest.raises(ConfigError, match=rf"^{re.escape(str(path))}: malformed YAML at line 3"):
        load_config(path)
    path.write_text("- just\n- a list\n")
    with pytest.raises(ConfigError, match="must hold a mapping, got list"):
        load_config(path)


def test_world_files_extending_each_other_are_a_clear_error(tmp_path):
    (tmp_path / "a.yaml").write_text(f"extends: {tmp_path / 'b.yaml'}\nname: a\n")
    (tmp_path / "b.yaml").write_text(f"extends: {tmp_path / 'a.yaml'}\nname: b\n")
    with pytest.raises(ConfigError, match="extend each other in a cycle"):
        load_config(world=str(tmp_path / "a.yaml"))


#: Numbers that may take any finite value (coordinates, signed offsets, reward weights).
ANY_FINITE = {
    "RobotConfig.camera_forward",
    "RewardConfig.progress",
    "RewardConfig.goal",
    "RewardConfig.collision",
    "RewardConfig.time",
    "FaultSpec.ticks",
}
#: Checked by the dataclass itself (``LandmarkPattern.__post_init__`` in stsf_gym.vision).
CHECKED_BY_OWNER = {f"LandmarkPattern.{n}" for n in ("square_size", "pitch", "grid", "border")}


def _unranged_numbers(cls: type, seen: set) -> list[str]:
    """``Class.field`` of every plain int/float field (no Range) below dataclass ``cls``."""
    found = []
    for name, hint in typing.get_type_hints(cls, include_extras=True).items():
        inner = [hint, *typing.get_args(hint)]
        for part in inner:
            if dataclasses.is_dataclass(part) and part not in seen:
                seen.add(part)
                found += _unranged_numbers(part, seen)
        if hint in (int, float):
            found.append(f"{cls.__name__}.{name}")
    return found


def test_every_number_in_the_env_config_has_a_range():
    unranged = set(_unranged_numbers(EnvConfig, set())) - ANY_FINITE - CHECKED_BY_OWNER
    assert not unranged, f"give these fields a Range (stsf_gym/validation.py): {sorted(unranged)}"
