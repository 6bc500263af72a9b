import math

import numpy as np
import pytest


@pytest.mark.parametrize("distance", [0.6, 1.5, 3.0])
def test_reads_known_wall_distance(make_env, distance):
    env = make_env("stsf_gym/Straight10m-v0", camera__enabled=False)
    env.reset(seed=0)
    cfg = env.unwrapped.config
    wall_face = 11.5 - cfg.world.wall_thickness / 2  # the far end wall, facing -x
    x = wall_face - cfg.robot.body_radius - 0.01 - distance  # sonar ring sits 1 cm outside the body
    readings = []
    for seed in range(30):
        obs, _ = env.reset(seed=seed, options={"start_pose": [x, 0.0, 0.0]})
        readings.append(obs["sonar"][0])
    readings = np.array(readings)
    sigma = cfg.sonar.noise_std + cfg.sonar.noise_std_per_m * distance
    valid = readings < cfg.sonar.max_range  # dropouts read max range
    assert valid.mean() > 0.8
    assert abs(np.mean(readings[valid]) - distance) < 3 * sigma / math.sqrt(valid.sum()) + 1e-3
    assert np.all(np.abs(readings[valid] - distance) < 5 * sigma)
    assert 0.3 * sigma < np.std(readings[valid]) < 2 * sigma


def test_noise_free_ring_geometry(make_env):
    env = make_env(
        camera__enabled=False,
        sonar__noise_std=0.0,
        sonar__noise_std_per_m=0.0,
        sonar__dropout_prob=0.0,
        sonar__rays_per_beam=1,
    )
    obs, _ = env.reset(seed=0, options={"start_pose": [5.0, 0.0, 0.0]})
    cfg = env.unwrapped.config
    lateral = 0.8 - cfg.world.wall_thickness / 2 - cfg.robot.body_radius - 0.01
    assert obs["sonar"][4] == pytest.approx(lateral, abs=1e-4)  # transducer 4 faces left (+90 deg)
    assert obs["sonar"][12] == pytest.approx(lateral, abs=1e-4)  # transducer 12 faces right
    assert obs["sonar"][0] == pytest.approx(cfg.sonar.max_range)  # nothing within range ahead
    assert obs["sonar"].dtype == np.float32 and obs["sonar"].shape == (16,)


def test_dropouts_read_max_range(make_env):
    env = make_env(camera__enabled=False, sonar__dropout_prob=1.0)
    obs, _ = env.reset(seed=0)
    assert np.all(obs["sonar"] == env.unwrapped.config.sonar.max_range)
