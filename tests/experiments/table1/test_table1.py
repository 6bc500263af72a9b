import json
import math
import subprocess
import sys

import numpy as np
import pytest

from stsf_gym.envs.config import load_config
from stsf_gym.experiments.table1.measure import Place, average_features, measure_rows, range_step
from stsf_gym.experiments.table1.run import (
    PAPER_TABLE1,
    SeedResult,
    focal_length,
    load_table1_config,
    run_seed,
    summarise,
)
from stsf_gym.results import check_rows
from stsf_gym.validation import ConfigError

F, CENTRE = 600.0, np.array([319.5, 239.5])
K = np.array([[F, 0, CENTRE[0]], [0, F, CENTRE[1]], [0, 0, 1]])
NORMAL = np.array([1.0, 0.0, 0.0])  # a board at the origin facing +x, as in table1_hall
SQUARES = np.array(
    [[0.0, y, z] for y in np.linspace(-0.2, 0.2, 5) for z in np.linspace(0.7, 1.1, 5)]
)
DISTANCES = [8.61, 7.81, 7.02, 6.28, 5.06, 5.52, 6.32]  # start place, then the paper's six


def camera_at(distance: float, approach_deg: float = 40.0) -> np.ndarray:
    """A camera on the rig's line of places, 0.9 m up, looking at the board centre."""
    lateral = math.tan(math.radians(approach_deg)) * (6.835 - distance)
    return np.array([distance, lateral, 0.9])


HEADING = math.radians(180 - 40)  # along the line of places, towards the board's wall


def synthetic_places(distances=DISTANCES, heading=HEADING) -> list[Place]:
    """Noise-free places: the squares projected exactly, odometry exact (camera on the axle)."""
    places, previous = [], None
    for distance in distances:
        eye = camera_at(distance)
        forward = np.array([0.0, 0.9, 0.9]) - eye
        forward /= np.linalg.norm(forward)
        down = np.array([0.0, 0.0, -1.0]) - forward * -forward[2]
        down /= np.linalg.norm(down)
        rotation = np.column_stack([np.cross(down, forward), down, forward])
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = rotation, eye
        in_camera = (SQUARES - eye) @ rotation
        pixels = F * in_camera[:, :2] / in_camera[:, 2:] + CENTRE
        moved = np.zeros(2) if previous is None else eye[:2] - previous[:2]
        turn = np.array(
            [[math.cos(heading), math.sin(heading)], [-math.sin(heading), math.cos(heading)]]
        )
        places.append(
            Place(
                points=dict(enumerate(pixels)),
                frames=10,
                world_from_camera=pose,
                heading=heading,
                motion=np.array([*(turn @ moved), 0.0]),
                motion_cov=np.diag([1e-6, 1e-6, 1e-8]),
            )
        )
        previous = eye
    return places


def rows_of(places):
    return measure_rows(places, K, NORMAL, 0.5, camera_forward=0.0)


def test_both_methods_recover_the_distances_from_exact_data():
    rows = rows_of(synthetic_places())
    np.testing.assert_allclose(rows["conventional"], DISTANCES[1:], rtol=1e-6)
    np.testing.assert_allclose(rows["stsf"], DISTANCES[1:], rtol=1e-6)
    np.testing.assert_allclose(rows["stsf_gls"], DISTANCES[1:], rtol=1e-6)
    assert rows["stsf"][0] == pytest.approx(rows["conventional"][0])  # row 1: the same for both


@pytest.mark.parametrize("place", [0, 2, 5])
def test_each_method_uses_the_places_of_the_protocol(place):
    """Disturbing one place's features changes conventional rows place and place+1 only
    (pairs k-1, k) and STSF from row ``place`` on (it fuses every place so far)."""
    clean = rows_of(synthetic_places())
    places = synthetic_places()
    places[place].points = {i: p + np.array([0.02, -0.01]) for i, p in places[place].points.items()}
    moved = rows_of(places)
    rows = np.arange(1, len(DISTANCES))
    changed = {
        name: ~np.isclose(moved[name], clean[name], rtol=1e-9, atol=0)
        for name in ("conventional", "stsf")
    }
    np.testing.assert_array_equal(changed["conventional"], (rows == place) | (rows == place + 1))
    np.testing.assert_array_equal(changed["stsf"], rows >= max(place, 1))


def test_stsf_carries_earlier_places_by_odometry():
    """A wrong odometry leg between places 2 and 3 moves STSF from row 3 on (carried
    measurements) while the conventional rows ignore the distance driven along the normal."""
    places = synthetic_places()
    places[3].motion = places[3].motion + np.array(
        [0.05, 0.0, 0.0]
    )  # odometry overshoots: nearer by 5 cm x cos 40°
    step, _ = range_step(places[2], places[3], NORMAL, 0.0)
    clean_step, _ = range_step(synthetic_places()[2], synthetic_places()[3], NORMAL, 0.0)
    assert clean_step - step == pytest.approx(0.05 * math.cos(math.radians(40)), rel=1e-6)
    rows, clean = rows_of(places), rows_of(synthetic_places())
    assert rows["stsf"][:2] == pytest.approx(clean["stsf"][:2])
    assert abs(rows["stsf"][2] - clean["stsf"][2]) > 1e-3


def test_a_place_without_the_board_leaves_gaps_not_errors():
    places = synthetic_places()
    places[3].points = {}
    rows = rows_of(places)
    assert math.isnan(rows["conventional"][2]) and math.isnan(rows["conventional"][3])
    assert rows["stsf"][2] == pytest.approx(DISTANCES[3], rel=1e-6)  # earlier rows carried on
    assert rows["stsf"][4] == pytest.approx(DISTANCES[5], rel=1e-6)


def test_features_are_averaged_over_the_frames_that_found_them():
    frames = [{0: np.array([1.0, 2.0]), 1: np.array([5.0, 5.0])}, {0: np.array([3.0, 4.0])}, {}]
    averaged = average_features(frames)
    assert set(averaged) == {0}  # square 1 was found in one frame of three
    np.testing.assert_allclose(averaged[0], [2.0, 3.0])


def test_summary_rows_have_the_paper_the_bound_and_the_baselines():
    cfg = load_table1_config(distances=[7.81, 7.02], seeds=2)
    results = [
        SeedResult(
            [7.8, 7.0],
            [1.0, 1.0],
            [1.0, 1.0],
            [0.0, 0.01],
            [10, 10],
            [8.0, 7.3],
            [8.0, 7.1],
            [8.0, 7.2],
        ),
        SeedResult(
            [7.8, 7.0],
            [1.2, 1.0],
            [1.2, 1.0],
            [0.0, -0.01],
            [10, 10],
            [7.6, 6.9],
            [7.6, 6.95],
            [7.6, 7.0],
        ),
    ]
    rows = summarise(cfg, results)
    check_rows(rows)
    assert [row["world_distance_m"] for row in rows] == [7.81, 7.02]
    assert rows[0]["conventional_rms_error_m"] == pytest.approx(0.2)
    assert rows[1]["conventional_error_m"]["std"] == pytest.approx(0.2)  # +0.3 and -0.1
    assert rows[1]["stsf_rms_error_m"] == pytest.approx(math.sqrt((0.1**2 + 0.05**2) / 2))
    assert rows[0]["baseline_m"]["mean"] == pytest.approx(1.1)
    assert rows[1]["paper_conventional_error_m"] == PAPER_TABLE1[1][2]
    assert rows[1]["paper_stsf_error_m"] == PAPER_TABLE1[1][4]
    bound = math.sqrt(2) * 7.81**2 * 0.5 / (focal_length(cfg) * 1.1)
    assert rows[0]["bound_m"] == pytest.approx(bound)
    assert focal_length(cfg) == pytest.approx(240 / math.tan(math.radians(22.5)))  # 640x480, 45°


def test_the_default_protocol_is_the_papers():
    cfg = load_table1_config()
    assert list(cfg.distances) == [row[0] for row in PAPER_TABLE1]
    assert cfg.start_distance > cfg.distances[0]  # row 1's pair: the robot approaches
    assert cfg.frames_per_place == 10 and cfg.sigma_px == 0.5 and cfg.seeds == 20
    camera = load_config(cfg.env).camera
    assert (camera.width, camera.height, camera.profile, camera.mode) == (
        640,
        480,
        "paper",
        "rendered",
    )
    assert camera.feature_rms_px == 0.5  # the profile gives the paper's feature noise


def test_bad_experiment_keys_and_values_are_named():
    with pytest.raises(ConfigError, match=r"table1\.frames"):
        load_table1_config(frames=3)
    with pytest.raises(ValueError, match=r"table1\.distances"):
        load_table1_config(distances=[7.0, -1.0])


@pytest.fixture(scope="module")
def rig_run():
    """The rendered rig: start at 7.81 m, approach to 7.02 and 6.28 m, recede to 6.60 m."""
    cfg = load_table1_config(start_distance=7.81, distances=[7.02, 6.28, 6.6], frames_per_place=3)
    return cfg, run_seed(cfg, seed=0)


@pytest.mark.slow
def test_the_rig_stops_at_the_places_and_drives_the_baselines(rig_run):
    cfg, result = rig_run
    np.testing.assert_allclose(result.truth, cfg.distances, atol=0.01)
    steps = np.abs(np.diff([cfg.start_distance, *cfg.distances]))
    along_line = steps / math.cos(math.radians(cfg.approach_deg))  # the line's slant to the normal
    np.testing.assert_allclose(result.baseline, along_line, atol=0.02)
    np.testing.assert_allclose(result.odometry_baseline, result.baseline, atol=0.02)
    assert result.frames == [3, 3, 3]  # every frame of every place found the board
    assert all(abs(e) < 0.02 for e in result.heading_error)


def test_the_rendered_rig_measures_the_distances(rig_run):
    _, result = rig_run
    errors = np.array(result.conventional) - result.truth
    assert np.all(np.isfinite(errors)) and np.all(np.abs(errors) < 2.0)
    assert result.stsf[0] == result.conventional[0]


@pytest.mark.slow
def test_cli_reproduce_table1_json(tmp_path):
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "stsf_gym.cli",
            "reproduce",
            "table1",
            "--json",
            "--out",
            str(tmp_path),
            "--seeds",
            "1",
            "--workers",
            "1",
            "--set",
            "frames_per_place=2",
            "--set",
            "start_distance=5.52",
            "--set",
            "distances=[5.06]",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    rows = json.loads(result.stdout)["rows"]
    assert len(rows) == 1 and rows[0]["conventional_m"]["count"] == 1
    check_rows(rows)
    assert isinstance(rows[0]["conventional_rms_error_m"], float)
    assert (tmp_path / "table1" / "table1.png").stat().st_size > 10_000
    assert "| row |" in (tmp_path / "table1" / "table1.md").read_text()
