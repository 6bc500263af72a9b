"""Fault injection: each fault kind's effect on the raw observation, determinism, and the
estimators surviving (finite estimate, positive definite covariance) and recovering."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from stsf_gym.envs.config import load_config
from stsf_gym.estimators.frame_detector import FrameDetector
from stsf_gym.experiments.episodes import EpisodeSpec, run_episode
from stsf_gym.experiments.fault_runs import recovery
from stsf_gym.results import check_rows
from stsf_gym.validation import ConfigError

STRAIGHT = "stsf_gym/Straight10m-v0"
SIMULATED = {"camera__mode": "fast"}  # detections simulated: the camera faults without rendering
RECOVERY_DISTANCE = 1.0  # m driven after a kidnap or a spike until the error is back in bounds
#: The paper's conventional fusion keeps nothing between pairs: after re-localising, each
#: estimate is one pair's measurement, and a poor one (a board nearly ahead) takes it out of
#: bounds again until better pairs come (measured: 0.75 m after the kidnap below, 2.24 m after
#: the encoder spike; 1.81 m after the kidnap before the chassis was levelled and each
#: subsystem drew from its own random stream).
PAIR_ONLY_RECOVERY_DISTANCE = 2.5


@pytest.mark.parametrize(
    ("fault", "message"),
    [
        ({"kind": "kidnap", "start": 3.0, "shift": [0.1, 0.0]}, "faults[0].turn_deg is required"),
        (
            {"kind": "camera_blackout", "duration": 2.0, "ticks": 5},
            "faults[0].ticks is not a parameter of kind 'camera_blackout'",
        ),
        ({"kind": "landmark_removed", "landmark_id": 42}, "faults[0].landmark_id must be"),
        ({"kind": "sonar_dropouts", "duration": 1.0, "probability": 1.5}, "probability must be"),
        ({"kind": "encoder_spike", "wheel": "left", "ticks": 9}, "faults[0].start of an instant"),
    ],
)
def test_bad_fault_is_named(fault, message):
    assert load_config().faults == ()  # none by default
    with pytest.raises(ConfigError, match=message.replace("[", r"\[").replace("]", r"\]")):
        load_config(faults=[fault])


def run(env, steps: int, seed: int = 0, action=(0.4, 0.0)):
    """Reset and drive straight; the (obs, info) of every step, reset included, with the
    landmarks in view then in ``info["in_view"]``."""
    obs, info = env.reset(seed=seed)
    history = [(obs, {**info, "in_view": env.unwrapped.landmarks_in_view()})]
    for _ in range(steps):
        obs, _, terminated, truncated, info = env.step(np.asarray(action, np.float32))
        history.append((obs, {**info, "in_view": env.unwrapped.landmarks_in_view()}))
        assert not (terminated or truncated)
    return history


def during(history, start: float, end: float):
    return [(o, i) for o, i in history if start - 1e-9 <= i["sim_time"] < end - 1e-9]


def test_world_faults_on_rendered_frames(make_env):
    faults = [
        {"kind": "camera_blackout", "start": 1.0, "duration": 1.0},
        {"kind": "dropped_frames", "start": 2.0, "duration": 1.0, "probability": 1.0},
        {"kind": "landmark_occluded", "start": 3.0, "duration": 1.0, "landmark_id": 1},
        {"kind": "outlier_detection", "start": 4.0, "duration": 1.0, "landmark_id": 3}
        | {"at": [3.2, 1.2], "facing_deg": -90.0},
        {"kind": "encoder_spike", "start": 5.0, "wheel": "right", "ticks": 300},
        {"kind": "kidnap", "start": 5.5, "shift": [0.3, -0.1], "turn_deg": 10.0},
    ]
    # the ideal camera: the decoy 2-3 m off to the side is detected in every frame it shows
    env = make_env(STRAIGHT, faults=faults, camera__pan_deg=40.0, camera__profile="ideal")
    history = run(env, 60)
    frames = [(o, i) for o, i in history if o["image_new"]]
    assert all(o["image"].max() > 0 for o, _ in during(history, 0.0, 1.0))
    assert all(o["image"].max() == 0 for o, _ in during(history, 1.0, 2.0))  # dark
    dropped = during(history, 2.0, 3.0)
    assert not any(o["image_new"] for o, _ in dropped)  # no frame arrives
    assert all(o["image"].max() == 0 for o, _ in dropped)  # the last one delivered repeats
    in_view = {round(i["sim_time"], 1): i["in_view"] for _, i in frames}
    assert 1 in in_view[1.8] and 1 not in in_view[3.4] and 1 in in_view[4.2]
    model = env.unwrapped
    detect = FrameDetector(model.config.world.landmark_pattern, {lm.id for lm in model.landmarks})
    seen = {round(i["sim_time"], 1): {d.landmark_id for d in detect(o)} for o, i in frames}
    assert 3 in seen[4.4] and 3 not in seen[3.8] and 3 not in seen[5.2]  # the decoy, in time
    ticks = np.array([o["encoders"] for o, _ in history[1:]])
    spike = round(5.0 / model.dt) - 1
    assert ticks[spike, 1] - ticks[spike, 0] > 250 and abs(np.diff(ticks[spike + 1])[0]) < 20
    jump = round(5.5 / model.dt)
    (_, before), (_, after) = history[jump - 1], history[jump]
    moved = after["true_pose"] - before["true_pose"]
    assert moved[:2] == pytest.approx([0.3, -0.1], abs=0.03)
    assert moved[2] == pytest.approx(math.radians(10.0), abs=0.01)
    assert after["distance_travelled"] - before["distance_travelled"] < 0.03  # not driven
    _obs, info = env.reset(seed=0)  # the next episode starts with every board in place
    assert 1 in env.unwrapped.landmarks_in_view(info["camera_pose"])


def test_sensor_faults_on_simulated_detections(make_env):
    faults = [
        {"kind": "camera_blackout", "start": 1.0, "duration": 1.0},
        {"kind": "outlier_detection", "start": 2.0, "duration": 1.0, "landmark_id": 4}
        | {"at": [3.2, 1.2], "facing_deg": -90.0},
        {"kind": "landmark_removed", "start": 3.0, "landmark_id": 1},
        {"kind": "sonar_dropouts", "start": 1.0, "duration": 1.0, "probability": 1.0},
        {"kind": "sonar_spurious", "start": 2.0, "duration": 1.0, "probability": 1.0}
        | {"max_range": 0.4},
    ]
    clean = run(make_env(STRAIGHT, **SIMULATED, camera__pan_deg=40.0), 50)
    faulty = run(make_env(STRAIGHT, **SIMULATED, camera__pan_deg=40.0, faults=faults), 50)
    assert all(1 in o["landmark_ids"] for o, _ in during(clean, 3.0, 5.0))
    assert not any(1 in o["landmark_ids"] for o, _ in during(faulty, 3.0, 5.0))  # removed
    assert all((o["landmark_ids"] == -1).all() for o, _ in during(faulty, 1.0, 2.0))
    assert all((o["sonar"] == 5.0).all() for o, _ in during(faulty, 1.0, 2.0))
    assert all((o["sonar"] <= 0.4).all() for o, _ in during(faulty, 2.0, 3.0))
    assert all((o["sonar"] > 0.4).any() for o, _ in during(faulty, 3.0, 4.0))
    for obs, _ in during(faulty, 2.0, 3.0):  # a detection of board 1 copied, labelled 4
        ids = obs["landmark_ids"]
        points = obs["landmark_points"].reshape(len(ids), -1, 2)
        (wrong,) = np.flatnonzero(ids == 4)
        (real,) = np.flatnonzero(ids == 1)
        np.testing.assert_array_equal(points[wrong], points[real])


def test_motion_blur_moves_simulated_points_along_the_blur(make_env):
    blur = {"kind": "motion_blur", "start": 0.5, "duration": 1.0, "kernel_px": 9.0}
    clean = run(make_env(STRAIGHT, **SIMULATED, camera__pan_deg=40.0), 6)
    faulty = run(
        make_env(STRAIGHT, **SIMULATED, camera__pan_deg=40.0, faults=[blur | {"angle_deg": 0}]), 6
    )
    # the first blurred frame (0.6 s): same simulated detection, then the blur's own error
    ids = faulty[6][0]["landmark_ids"]
    points, reference = (
        h[6][0]["landmark_points"].reshape(len(ids), -1, 2) for h in (faulty, clean)
    )
    assert faulty[6][0]["image_new"] and (ids >= 0).any()
    used = ids >= 0
    assert np.abs(points[used, :, 0] - reference[used, :, 0]).max() > 1.0
    np.testing.assert_array_equal(points[..., 1], reference[..., 1])  # along the rows only


def test_faults_are_deterministic(make_env):
    faults = [
        {"kind": "dropped_frames", "start": 0.5, "duration": 3.0, "probability": 0.5},
        {"kind": "sonar_dropouts", "start": 0.5, "duration": 3.0, "probability": 0.5},
        {"kind": "sonar_spurious", "start": 1.0, "duration": 3.0, "probability": 0.3}
        | {"max_range": 0.5},
        {"kind": "motion_blur", "start": 2.0, "duration": 2.0, "kernel_px": 5.0}
        | {"angle_deg": 30.0},
    ]
    runs = [
        run(make_env(STRAIGHT, **SIMULATED, camera__pan_deg=40.0, faults=faults), 40, seed)
        for seed in (3, 3, 4)
    ]

    def stream(history):
        return [np.concatenate([np.ravel(v) for v in o.values()]) for o, _ in history]

    first, again, other = (stream(h) for h in runs)
    for a, b in zip(first, again, strict=True):
        np.testing.assert_array_equal(a, b)
    assert any(not np.array_equal(a, b) for a, b in zip(first, other, strict=True))


KIDNAP = {"kind": "kidnap", "start": 15.0, "shift": [0.3, 0.15], "turn_deg": 8.0}
SPIKE = {"kind": "encoder_spike", "start": 15.0, "wheel": "left", "ticks": 300}


def fault_episode(estimator: str, fault: dict):
    """The follower on ``estimator`` along Straight10m for 40 s with one fault at 15 s."""
    env = {"camera": {"mode": "fast"}, "sim": {"max_episode_seconds": 40.0}, "faults": [fault]}
    episode = run_episode(EpisodeSpec("straight_10m", estimator, seed=1, env=env))
    assert episode.finite and episode.min_cov_eigenvalue > 0  # at every step
    return episode, recovery(episode, fault["start"], fault["start"])


@pytest.mark.slow
@pytest.mark.parametrize("fault", [KIDNAP, SPIKE], ids=["kidnap", "encoder_spike"])
@pytest.mark.parametrize("estimator", ["conventional", "conventional-filter", "stsf", "ekf"])
def test_landmark_estimators_recover(estimator, fault):
    episode, result = fault_episode(estimator, fault)
    assert max(np.abs(episode.heading_errors)) > 0.1  # the fault turned the estimate away
    limit = PAIR_ONLY_RECOVERY_DISTANCE if estimator == "conventional" else RECOVERY_DISTANCE
    assert result["recovered"] and result["distance"] < limit
    assert result["error_after"] < result["bound"]
    assert abs(episode.heading_errors[-1]) < 0.02 and episode.relocalised >= 1


@pytest.mark.slow
def test_odometry_survives_a_kidnap_but_never_recovers():
    episode, result = fault_episode("odometry", KIDNAP)
    assert not result["recovered"] and episode.errors[-1] > 0.3


def test_relocalisation_needs_agreeing_candidates():
    from stsf_gym.estimators.relocalise import Relocaliser

    rule = Relocaliser(after=3, inflation=4.0, gate=11.34)
    cov = np.diag([1e-4, 1e-4, 1e-4])
    mean = np.array([1.0, 0.0, 0.0])
    kidnapped = np.array([1.3, 0.1, 0.1])  # where the landmarks say the robot is
    assert rule.rejected(kidnapped, cov, mean) is None
    assert rule.rejected(np.array([6.0, 0.0, 3.0]), cov, mean) is None  # an outlier
    moved = np.array([1.5, 0.0, 0.0])  # the estimate drove 0.5 m on odometry meanwhile
    truth = np.array([1.3 + 0.5 * math.cos(0.1), 0.1 + 0.5 * math.sin(0.1), 0.1])
    assert rule.rejected(truth, cov, moved) is None  # two of the three agree: not yet
    pose, pose_cov = rule.rejected(truth, cov, moved)
    assert pose == pytest.approx(truth)  # the first and the two newest agree exactly
    assert np.all(np.linalg.eigvalsh(pose_cov) > 4 * 1e-4)  # inflated
    assert rule.candidates == []


def test_relocalisation_restarts_at_the_agreeing_candidates_mean():
    from stsf_gym.estimators.relocalise import Relocaliser

    rule = Relocaliser(after=3, inflation=4.0, gate=11.34)
    cov = np.diag([0.04, 0.04, 0.01])  # noisy candidates (a near, oblique board)
    mean = np.zeros(3)  # the estimate does not move: the candidates need no carrying
    for pose in ([2.1, 1.0, 0.05], [1.9, 1.0, -0.05]):
        assert rule.rejected(np.array(pose), cov, mean) is None
    pose, _ = rule.rejected(np.array([2.3, 1.0, 0.0]), cov, mean)
    assert pose == pytest.approx([2.1, 1.0, 0.0])  # not the newest candidate


@pytest.mark.slow
def test_evaluate_reports_fault_runs(tmp_path):
    from stsf_gym.experiments.evaluate import evaluate

    fault_file = tmp_path / "kidnap.yaml"
    fault_file.write_text(
        "faults:\n  - {kind: kidnap, start: 8.0, shift: [0.3, 0.1], turn_deg: 5}\n"
    )
    env = {"camera": {"mode": "fast"}, "sim": {"max_episode_seconds": 25.0}}
    summary, runs = evaluate(
        tmp_path / "out",
        ["odometry", "ekf"],
        1,
        world="straight_10m",
        workers=1,
        env=env,
        faults=[fault_file],
    )
    rows = {row["estimator"]: row for row in summary["rows"]}
    assert set(runs) == {"kidnap/odometry", "kidnap/ekf"}
    assert rows["ekf"]["fault_set"] == "kidnap" and rows["ekf"]["recovered_rate"]["mean"] == 1.0
    assert rows["odometry"]["recovered_rate"]["mean"] == 0.0
    assert rows["odometry"]["valid_rate"]["mean"] == 1.0
    check_rows(json.loads((tmp_path / "out" / "results.json").read_text())["rows"])
    assert "recovery distance (m)" in (tmp_path / "out" / "results.md").read_text()
    bad = tmp_path / "bad.yaml"
    bad.write_text("faults:\n  - {kind: kidnap, start: 8.0}\nsonar: {}\n")
    with pytest.raises(ConfigError, match=r"bad\.yaml"):
        evaluate(tmp_path / "out", ["ekf"], 1, world="straight_10m", env=env, faults=[bad])
