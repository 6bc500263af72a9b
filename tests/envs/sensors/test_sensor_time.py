"""Time in the sensors: timestamps on every observation, camera latency and jitter, a sonar
firing sequence, and late frames fused at their exposure time."""

import itertools

import numpy as np
import pytest

from stsf_gym.estimators import make_estimator
from stsf_gym.wrappers import PoseEstimateWrapper, sensor_model
from stsf_gym.wrappers.state_history import FRAME_KEYS, StateHistory

STRAIGHT = "stsf_gym/Straight10m-v0"
FAST = {"camera__mode": "fast", "camera__pan_deg": 30.0}  # a board in view from the start


def drive(env, steps, seed=0):
    history = [env.reset(seed=seed)]
    for k in range(steps):
        obs, _, _, _, info = env.step(np.float32([0.5, 0.05 * np.sin(k / 8)]))
        history.append((obs, info))
    return history


def test_zero_latency_frames_carry_their_step_time(make_env):
    env = make_env(STRAIGHT, **FAST)
    for obs, info in drive(env, 20):
        assert obs["encoders_time"][0] == pytest.approx(info["sim_time"])
        np.testing.assert_allclose(obs["sonar_time"], info["sim_time"])
        if obs["image_new"]:
            assert obs["image_time"][0] == pytest.approx(info["sim_time"])
    assert env.observation_space.contains(obs)


def test_paper_latency_delays_frames_with_jitter(make_env):
    env = make_env(STRAIGHT, camera__latency__profile="paper", **FAST)
    latency = env.unwrapped.config.camera.latency
    assert latency.delay_s == pytest.approx(0.127 + 0.332)
    history = drive(env, 60)
    frames = [(obs["image_time"][0], info["sim_time"]) for obs, info in history if obs["image_new"]]
    assert frames and history[1][0]["image_time"][0] == -1.0  # nothing available at first
    delays = np.array([now - exposure for exposure, now in frames])
    assert np.all(delays >= latency.delay_s - 1e-9)
    assert len(set(np.round(delays, 6))) > 1  # jitter (and the step grid) vary them
    exposures = [exposure for exposure, _ in frames]
    assert exposures == sorted(exposures)  # never overtaking
    # info["camera_pose"] is the shown frame's: its exposure's pose, not the current one
    zero = make_env(STRAIGHT, **FAST)
    poses = {round(info["sim_time"], 6): info["camera_pose"] for _, info in drive(zero, 60)}
    for obs, info in history:
        if obs["image_new"]:
            np.testing.assert_allclose(info["camera_pose"], poses[round(obs["image_time"][0], 6)])


def test_sonars_fire_in_sequence_with_their_own_times(make_env):
    order = [0, 8, 4, 12, 2, 10, 6, 14, 1, 9, 5, 13, 3, 11, 7, 15]
    env = make_env(
        STRAIGHT, camera__enabled=False, sonar__firing_order=order, sonar__firing_interval_s=0.03
    )
    history = drive(env, 12)
    cycle = history[5][0]["sonar_time"]  # 0.5 s: 16 firings at 0.03 s, one cycle
    assert [int(t) for t in np.argsort(cycle)] == order
    np.testing.assert_allclose(np.sort(cycle), 0.03 * np.arange(1, 17))
    for (before, _), (after, _) in itertools.pairwise(history):
        unchanged = after["sonar_time"] == before["sonar_time"]
        np.testing.assert_array_equal(after["sonar"][unchanged], before["sonar"][unchanged])
        assert np.sum(~unchanged) in (3, 4)  # 0.1 s at 0.03 s per firing


def _standing(stream, steps):
    """``stream`` and ``steps`` more steps standing still without frames."""
    last = stream[-1]
    still = [
        {
            **last,
            "encoders": np.zeros(2, np.int64),
            "image_new": 0,
            "encoders_time": last["encoders_time"] + 0.1 * (k + 1),
        }
        for k in range(steps)
    ]
    return [*stream, *still]


def _delayed(stream, steps):
    """The recorded zero-latency stream with each frame arriving ``steps`` steps later."""
    delayed = [{**obs, "image_new": 0} for obs in stream]
    for k, obs in enumerate(stream):
        if obs["image_new"] and 0 < k < len(stream) - steps:  # (the reset's frame is unused)
            late = delayed[k + steps]
            late.update({key: obs[key] for key in FRAME_KEYS if key in obs}, image_new=1)
    return delayed


@pytest.mark.parametrize("name", ["ekf", "stsf"])
def test_a_late_frame_fused_at_its_time_equals_the_prompt_one(make_env, name):
    """Rewind and replay give the estimate the frames would have given on time (to float
    precision); fusing them on arrival, as if current, does not."""
    env = make_env(STRAIGHT, **FAST)
    history = drive(env, 80)
    stream = _standing([obs for obs, _ in history], 5)
    model, start = sensor_model(env), env.unwrapped.config.world.start
    cov = np.diag([1e-4, 1e-4, 2.5e-5])

    def run(observations, state_history=None):
        estimator = make_estimator(name)
        estimator.reset(model, start, cov)
        if state_history is not None:
            state_history.reset(estimator, observations[0])
        mean = None
        for obs in observations[1:]:
            if state_history is None:
                mean, _ = estimator.update(obs, 0.1)
            else:
                estimator, mean, _ = state_history.update(estimator, obs, 0.1)
        return mean, estimator

    prompt, _ = run(stream)
    late = _delayed(stream, 5)
    replayed, estimator = run(late, StateHistory(1.0))
    naive, _ = run(late)
    np.testing.assert_allclose(replayed, prompt, atol=1e-9)
    assert np.abs(naive - prompt).max() > 1e-4
    assert estimator.counters["frames_late"] > 5 and estimator.counters["frames_too_late"] == 0
    _, dropped = run(late, StateHistory(0.3))  # too short a history: frames dropped, counted
    assert dropped.counters["frames_too_late"] > 5


def test_the_wrapper_fuses_late_frames(make_env):
    env = PoseEstimateWrapper(make_env(STRAIGHT, camera__latency__profile="paper", **FAST), "ekf")
    for obs, info in drive(env, 60):
        error = np.hypot(*(obs["pose"][:2] - info["true_pose"][:2]))
    assert env.estimator.counters["frames_late"] > 10 and error < 0.05
