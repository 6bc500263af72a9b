"""The robot's map in the policy's input, on hand-built poses: a board straight ahead reads its
range and zero bearing and is in the camera's sight, one behind a wall is not; the sonar the map
predicts at the true pose is the sonar measured there with its noise off."""

from __future__ import annotations

import numpy as np
import pytest

from stsf_gym.agents.rl.map_view import BOARD_HORIZON_M, MapView
from stsf_gym.episode_env import make_episode_env

SCALE = 4.0
QUIET_SONAR = {"noise_std": 0.0, "noise_std_per_m": 0.0, "dropout_prob": 0.0}


@pytest.fixture(scope="module")
def corridor():
    env = make_episode_env(
        "irl_corridor", "truth", {"camera": {"enabled": False}, "sonar": QUIET_SONAR}
    )
    env.reset(seed=0)
    yield env
    env.close()


def test_a_board_straight_ahead_reads_its_range_and_zero_bearing(corridor):
    board = next(lm for lm in corridor.unwrapped.landmarks if lm.id == 5)  # the first leg's end
    distance = 1.3  # nearer than any other board, beyond the pointing's 1 m least range
    xy = board.centre[:2] + distance * board.normal[:2]  # in front of it, on its normal
    yaw = np.arctan2(-board.normal[1], -board.normal[0])  # facing it
    view = MapView(corridor, SCALE)
    features = view.boards(np.array([*xy, yaw]), 2)
    assert features[:4] == pytest.approx([distance / SCALE, 0.0, 1.0, 1.0], abs=1e-9)
    turned = view.boards(np.array([*xy, yaw + np.pi / 2]), 1)  # the board now on its right
    assert turned[1:3] == pytest.approx([-1.0, 0.0], abs=1e-9)
    away = view.boards(np.array([*xy, yaw + np.pi]), 1)  # behind it: beyond the pan limit
    assert away[1:3] == pytest.approx([0.0, -1.0], abs=1e-9) and away[3] == 0.0
    behind_a_wall = view.boards(np.array([1.0, 0.0, 0.0]), 8).reshape(-1, 4)
    assert behind_a_wall[-1, 3] == 0.0  # the farthest board, up the second leg, is out of sight


def test_missing_boards_read_as_out_of_sight_at_the_horizon(corridor):
    count = len(corridor.unwrapped.landmarks)
    features = MapView(corridor, SCALE).boards(np.array([1.0, 0.0, 0.0]), count + 2)
    assert features.shape == ((count + 2) * 4,)
    assert features[-4:] == pytest.approx([BOARD_HORIZON_M / SCALE, 0.0, 1.0, 0.0])


def test_the_predicted_sonar_is_the_measured_sonar_on_the_true_pose_with_noise_off(corridor):
    view = MapView(corridor, SCALE)
    sonar = corridor.unwrapped.config.sonar
    obs = None
    for _ in range(40):
        obs, *_ = corridor.step(np.array([0.5, 0.2], np.float32))
    predicted = view.sonar(obs["pose"]) * (sonar.max_range - sonar.min_range) + sonar.min_range
    assert predicted == pytest.approx(obs["sonar"], abs=1e-4)
    moved = view.sonar(obs["pose"] + np.array([0.3, 0.0, 0.0]))
    assert not np.allclose(moved, view.sonar(obs["pose"]))  # it reads the pose it is given


def test_the_policy_input_grows_by_the_map_entries_it_is_asked_for():
    from stsf_gym.agents.rl.ready import make_rl_env

    plain = make_rl_env("corridor", "truth")
    mapped = make_rl_env("corridor", "truth", observation={"boards": 3, "predicted_sonar": True})
    try:
        assert mapped.observation_space.shape[0] == plain.observation_space.shape[0] + 12 + 16
        obs, _ = mapped.reset(seed=0)
        assert mapped.observation_space.contains(obs)
    finally:
        plain.close()
        mapped.close()
