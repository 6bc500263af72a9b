"""The measures of what an agent does near its goals, on hand-built episodes whose answers are
known: a robot that drives 2 m at 0.1 m/s, waits 5 s and declares; one that never slows."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from stsf_gym.experiments.benchmark.agent_behaviour import behaviour_row, episode_behaviour
from stsf_gym.experiments.episodes import full_covariances


def _episode(speeds: list[float], stop_sigma: float, outcome: str = "goal") -> SimpleNamespace:
    """A straight drive along x at ``speeds`` (one per 0.1 s step), declared at its end."""
    x = np.concatenate([[0.0], np.cumsum(np.asarray(speeds) * 0.1)])
    times = np.arange(len(x)) * 0.1
    covariances = [[0.04, 0, 0, 0.04, 0, 0.01]] * (len(x) - 1) + [
        [stop_sigma**2, 0, 0, stop_sigma**2 / 4, 0, 0.01]
    ]
    stop = {"time": float(times[-1]), "true_distance_m": 0.05}
    return SimpleNamespace(
        times=times.tolist(),
        travelled=x.tolist(),
        true_poses=[[float(v), 0.0, 0.0] for v in x],
        covariances=covariances,
        stops=[stop],
        path_errors=[0.0, 0.3, 0.1],
        camera_frames=10,
        frames_in_view=4,
        outcome=outcome,
    )


def test_a_wait_before_the_stop_shows_in_the_approach():
    waits = episode_behaviour(_episode([0.1] * 200 + [0.0] * 50, stop_sigma=0.1))
    # 10 s for the last metre and 5 waiting, to one 0.1 s step
    assert waits["approach_time_s"] == [pytest.approx(15.0, abs=0.11)]
    assert waits["approach_speed_mps"] == [pytest.approx(1.0 / 15.0, rel=0.01)]
    assert waits["stop_sigma_m"] == [pytest.approx(0.1)]
    cruises = episode_behaviour(_episode([0.1] * 200, stop_sigma=0.3, outcome="collision"))
    assert cruises["approach_time_s"] == [pytest.approx(10.0, abs=0.11)]
    assert cruises["approach_speed_mps"] == [pytest.approx(0.1)]
    assert cruises["largest_path_distance_m"] == 0.3 and cruises["boards_in_view_share"] == 0.4
    row = behaviour_row([waits, cruises])
    assert row["collision"]["mean"] == 0.5 and row["success"]["mean"] == 0.5
    assert row["stop_sigma_m"]["mean"] == pytest.approx(0.2)


def test_covariances_unfold_from_their_upper_triangles():
    full = full_covariances([[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]])[0]
    assert full.tolist() == [[1, 2, 3], [2, 4, 5], [3, 5, 6]]
