"""Property-based tests (hypothesis): the fusion functions keep their algebra, and every
estimator stays finite and positive definite on any valid measurement stream.

The streams start from one recorded episode (the follower on the IRL corridor, fast sensor
mode, the camera pointed as in every evaluation); hypothesis then drops camera frames, takes
boards out of view for a while (a board vanishing and reappearing), and merges runs of control
steps into long gaps (the encoder ticks summed, the time step lengthened), in any combination.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from stsf_gym.agents.follower import PathFollower
from stsf_gym.episode_env import make_episode_env
from stsf_gym.estimators import ESTIMATORS, make_estimator
from stsf_gym.fusion import (
    DegenerateGeometryError,
    merge_gaussians,
    motion_stereo_range,
    spatial_fusion,
)
from stsf_gym.wrappers import sensor_model

SEEDS = st.integers(0, 2**32 - 1)
STEPS = 700  # 70 s of driving: the start, several boards, the approach to the turn
ALGEBRA = settings(max_examples=60, deadline=None)
STREAMS = settings(
    max_examples=10, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)


def _spd(rng: np.random.Generator, m: int, scale: float = 1.0) -> np.ndarray:
    a = rng.normal(size=(m, m)) * scale
    return a @ a.T + 1e-3 * scale**2 * np.eye(m)


def _loewner_le(small: np.ndarray, large: np.ndarray) -> bool:
    """``small <= large`` in the positive semi-definite order (to rounding)."""
    return np.linalg.eigvalsh(large - small).min() >= -1e-9 * np.abs(large).max()


@given(SEEDS, st.integers(1, 4))
@ALGEBRA
def test_a_merge_is_never_more_uncertain_than_its_most_certain_input(seed, m):
    rng = np.random.default_rng(seed)
    C1, C2 = _spd(rng, m, rng.uniform(0.01, 10)), _spd(rng, m, rng.uniform(0.01, 10))
    x, C = merge_gaussians(rng.normal(size=m), C1, rng.normal(size=m), C2)
    assert np.isfinite(x).all()
    assert _loewner_le(C, C1) and _loewner_le(C, C2)
    np.testing.assert_allclose(C, C.T, atol=1e-12 * np.abs(C).max())


@given(SEEDS, st.integers(2, 6), st.integers(1, 3))
@ALGEBRA
def test_spatial_fusion_ignores_the_order_of_its_inputs(seed, n, m):
    rng = np.random.default_rng(seed)
    xs = rng.normal(size=(n, m))
    covs = np.stack([_spd(rng, m, rng.uniform(0.05, 3)) for _ in range(n)])
    x, C = spatial_fusion(xs, covs=covs)
    order = rng.permutation(n)
    x_p, C_p = spatial_fusion(xs[order], covs=covs[order])
    np.testing.assert_allclose(x_p, x, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(C_p, C, rtol=1e-9, atol=1e-12)
    for cov in covs:  # never more uncertain than the most certain measurement
        assert _loewner_le(C, cov)


@given(SEEDS, st.floats(0.0, 1e-9), st.integers(1, 4))
@ALGEBRA
def test_motion_stereo_without_baseline_reports_degenerate_geometry(seed, baseline, n):
    rng = np.random.default_rng(seed)
    points = np.column_stack([rng.uniform(-1, 1, (n, 2)), rng.uniform(2, 8, n)])
    f = 400.0
    q = np.column_stack([f * points[:, :2] / points[:, 2:], np.full(n, f)])
    t = baseline * rng.normal(size=3)
    try:
        depth = motion_stereo_range(q, q, np.eye(3), t, np.array([0.0, 0.0, 1.0]))
    except DegenerateGeometryError:
        return
    assert np.isfinite(depth).all()  # never inf or NaN: either a number or the error


@pytest.fixture(scope="module")
def recorded():
    """One episode's raw observations as the estimators receive them, its sensor model and
    start pose, and the control period."""
    env = make_episode_env("irl_corridor", "truth", {"camera__mode": "fast"})
    try:
        obs, _ = env.reset(seed=3)
        follower = PathFollower.for_env(env)
        model, start = sensor_model(env), np.asarray(env.unwrapped.config.world.start, float)
        stream = []
        for _ in range(STEPS):
            obs, _, terminated, truncated, _ = env.step(follower.act(obs["pose"], obs["sonar"]))
            stream.append({k: v for k, v in obs.items() if k not in ("pose", "pose_cov")})
            if terminated or truncated:
                break
        return stream, model, start, env.unwrapped.dt
    finally:
        env.close()


@st.composite
def mutations(draw):
    """Dropped frames (indices), a board out of view over a window, and merged step runs."""
    dropped = draw(st.sets(st.integers(0, STEPS - 1), max_size=80))
    vanish = draw(st.tuples(st.integers(0, 7), st.integers(0, STEPS - 1), st.integers(1, 120)))
    gaps = draw(st.lists(st.tuples(st.integers(0, STEPS - 1), st.integers(2, 40)), max_size=4))
    return dropped, vanish, gaps


def mutate(stream: list[dict], dt: float, plan) -> list[tuple[dict, float]]:
    """The stream with ``plan`` applied, as ``(obs, dt)`` pairs."""
    dropped, (board, start, length), gaps = plan
    out = []
    for i, obs in enumerate(stream):
        obs = {k: np.array(v, copy=True) for k, v in obs.items()}
        if i in dropped:
            obs["image_new"] = np.int64(0)
        if start <= i < start + length and "landmark_ids" in obs:
            obs["landmark_ids"][obs["landmark_ids"] == board] = -1
        out.append((obs, dt))
    for first, count in sorted(gaps, reverse=True):
        run = out[first : first + count]
        if len(run) < 2:
            continue
        merged = dict(run[-1][0])
        merged["encoders"] = np.sum([obs["encoders"] for obs, _ in run], axis=0)
        out[first : first + count] = [(merged, sum(step for _, step in run))]
    return out


@pytest.mark.slow
@pytest.mark.parametrize("name", list(ESTIMATORS))
@given(plan=mutations())
@STREAMS
def test_every_estimator_stays_finite_and_positive_definite(recorded, name, plan):
    stream, model, start, dt = recorded
    estimator = make_estimator(name)
    estimator.reset(model, start, np.diag([1e-4, 1e-4, 2.5e-5]))
    for step, (obs, step_dt) in enumerate(mutate(stream, dt, plan)):
        mean, cov = estimator.update(obs, step_dt)
        assert np.isfinite(mean).all() and np.isfinite(cov).all(), f"{name} at step {step}"
        np.testing.assert_allclose(cov, cov.T, atol=1e-9 * np.abs(cov).max() + 1e-15)
        assert np.linalg.eigvalsh(cov).min() > 0, f"{name}: not positive definite at {step}"


def test_the_recorded_stream_exercises_the_landmark_estimators(recorded):
    stream, *_ = recorded
    frames = [obs for obs in stream if obs["image_new"]]
    seen = {int(i) for obs in frames for i in obs.get("landmark_ids", []) if i >= 0}
    assert len(frames) > 100 and len(seen) >= 3  # frames with boards: the mutations matter
