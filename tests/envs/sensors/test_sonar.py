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


BEAM = {"sonar__beam__enabled": True, "sonar__noise_std": 0.0, "sonar__noise_std_per_m": 0.0}


def _readings(env, reads=60):
    """Ring readings of the robot standing mid-corridor, facing along it (x)."""
    env.reset(seed=0, options={"start_pose": [4.0, 0.0, 0.0]})
    unwrapped = env.unwrapped
    return np.array(
        [
            unwrapped.sonar.read(unwrapped.sim, unwrapped._pose, unwrapped.streams.sonar)
            for _ in range(reads)
        ]
    )


def test_beam_model_detection_falls_with_incidence():
    from stsf_gym.envs.config import load_config
    from stsf_gym.envs.sensors.sonar_beam import detection_probability

    beam = load_config().sonar.beam
    p = detection_probability(np.radians([0.0, beam.critical_angle_deg, 60.0]), beam)
    assert p[0] > 0.99 and p[1] == pytest.approx(0.5) and p[2] < 0.01


def test_beam_model_misses_oblique_walls_and_sees_square_ones(make_env):
    """Mid-corridor (walls 1.2 m to each side): transducer 4 meets the left wall head-on and
    reads it; transducer 1 meets it at about 67 deg and misses it (max range) nearly always,
    where the ideal ring reads the wall at about 2.6 m."""
    ideal = _readings(
        make_env("stsf_gym/Straight10m-v0", camera__enabled=False, sonar__dropout_prob=0.0)
    )
    beam = _readings(
        make_env("stsf_gym/Straight10m-v0", camera__enabled=False, sonar__dropout_prob=0.0, **BEAM)
    )
    max_range = 5.0
    assert np.all(ideal[:, 1] < 3.0)
    assert np.mean(beam[:, 1] >= max_range - 1e-6) > 0.9  # specular miss
    assert np.median(beam[:, 4]) == pytest.approx(ideal[0, 4], abs=0.02)  # head-on: read


def test_crosstalk_only_when_the_ring_fires_together(make_env):
    crosstalk = {**BEAM, "sonar__beam__crosstalk_prob": 1.0, "sonar__beam__random_prob": 0.0}
    together = _readings(
        make_env("stsf_gym/Straight10m-v0", camera__enabled=False, **crosstalk), 200
    )
    order = list(range(16))
    sequenced = make_env(
        "stsf_gym/Straight10m-v0",
        camera__enabled=False,
        sonar__firing_order=order,
        sonar__firing_interval_s=0.01,
        **crosstalk,
    )
    alone = _readings(sequenced, 200)
    # transducer 2 meets the left wall at 45 deg and mostly misses it; its neighbour 3 reads it
    # at 1.3 m: firing together, 2 takes 3's echo half the time
    assert np.mean(together[:, 2] < 4.0) > 0.4
    assert np.mean(alone[:, 2] < 4.0) < 0.3
