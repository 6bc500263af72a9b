"""The views people watch: the top-down map with the wrappers' estimate and camera target
(asked for in the render path), the chase camera, the human window's guard."""

import os
import shutil
import subprocess
import sys

import cv2
import numpy as np
import pytest
from helpers import ROOT

from stsf_gym.envs.rendering.map_view import ESTIMATE_COLOURS, INSET_FRACTION, TRUTH
from stsf_gym.validation import ConfigError
from stsf_gym.wrappers import CameraPointingWrapper, PoseEstimateWrapper


def _colour_near(frame: np.ndarray, pixel, colour, radius: int = 3) -> bool:
    u, v = pixel
    patch = frame[v - radius : v + radius + 1, u - radius : u + radius + 1].astype(int)
    return bool(np.any(np.abs(patch - colour).sum(axis=2) < 40))


def test_map_is_the_default_view_and_needs_no_renderer(make_env):
    env = make_env(render_mode="rgb_array", camera__enabled=False)
    assert env.unwrapped.renderer == "none"  # drawn in 2-D: no PyBullet rendering
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (360, 480, 3) and frame.dtype == np.uint8
    pose = env.unwrapped._pose
    assert _colour_near(frame, env.unwrapped.view.px(pose[:2]), TRUTH)
    assert make_env().unwrapped.view is None  # nothing to draw without a render mode


def test_map_shows_the_wrappers_estimate_with_its_two_sigma_ellipse(make_env):
    env = PoseEstimateWrapper(
        make_env(render_mode="rgb_array", camera__mode="fast"), "ekf", start_std=(0.3, 0.1, 0.05)
    )
    env.reset(seed=0, options={"start_pose": [3.0, 0.0, 0.0]})
    view = env.unwrapped.view
    frame = env.render()
    colour = ESTIMATE_COLOURS[0]
    # 2 sigma: 0.6 m along x, 0.2 m along y from the start
    assert _colour_near(frame, view.px([3.6, 0.0]), colour, 1)
    assert _colour_near(frame, view.px([3.0, 0.2]), colour, 1)
    assert not _colour_near(frame, view.px([3.0, 0.45]), colour, 1)
    for _ in range(5):
        obs, *_ = env.step(np.float32([0.5, 0.0]))
    # the legend names the estimator; the cross sits on the current estimate
    assert _colour_near(env.render(), view.px(obs["pose"][:2]), colour, 1)
    env.reset(seed=1, options={"start_pose": [6.0, 0.0, 0.0]})  # drawn again after a reset
    assert _colour_near(env.render(), view.px([6.0, 0.0]), colour, 1)


def test_the_map_asks_its_sources_at_each_frame_it_draws(make_env):
    """Estimates reach the map by the render path: the view asks each source when it draws,
    nothing is handed over when no frame is drawn."""
    env = make_env(render_mode="rgb_array", camera__enabled=False)
    asked = []

    def source():
        asked.append(True)
        return {"mine": ([4.0, 0.0, 0.0], np.diag([0.04, 0.01, 0.01]))}, ()

    env.unwrapped.draw_on_map(source)
    env.reset(seed=0)
    env.step(np.float32([0.5, 0.0]))
    assert not asked
    frame = env.render()
    assert asked == [True]
    assert _colour_near(frame, env.unwrapped.view.px([4.4, 0.0]), ESTIMATE_COLOURS[0], 1)


def test_map_rings_the_landmark_the_pointing_wrapper_keeps_the_camera_on(make_env):
    corridor = make_env(render_mode="rgb_array", camera__mode="fast", camera__control="pan")
    env = CameraPointingWrapper(PoseEstimateWrapper(corridor, "truth"))
    env.reset(seed=0, options={"start_pose": [2.0, 0.0, 0.0]})  # board 1 ahead on the left
    for _ in range(10):
        env.step(np.float32([0.5, 0.0]))
    target = env.pointer.target
    assert target is not None
    ringed = env.render()
    env.pointer.reset()  # no target: the same frame without the ring
    rows, cols = np.nonzero(np.any(ringed != env.render(), axis=2))
    u, v = env.unwrapped.view.px(env.unwrapped.view.landmarks[target].centre[:2])
    radius = np.hypot(cols - u, rows - v)
    assert len(radius) > 50 and np.all(np.abs(radius - 9) < 3.5)  # 9 px, 2 px wide, smoothed


def test_map_inset_is_the_current_camera_frame(make_env):
    env = make_env(render_mode="rgb_array")
    obs, _ = env.reset(seed=0)
    for _ in range(3):
        obs, *_ = env.step(np.float32([0.5, 0.3]))
    frame = env.render()
    w = round(480 * INSET_FRACTION)
    h = round(w * 240 / 320)
    expected = cv2.resize(obs["image"], (w, h), interpolation=cv2.INTER_AREA)
    corners = [frame[t : t + h, x : x + w] for t in (4, 360 - h - 4) for x in (4, 480 - w - 4)]
    assert sum(np.array_equal(c, expected) for c in corners) == 1


def test_chase_camera_films_from_inside_the_corridor(make_env):
    env = make_env(render_mode="rgb_array", render__view="chase", camera__enabled=False)
    env.reset(seed=0)  # the start faces away from the start cap, 1 m behind the robot
    distance = env.unwrapped._chase_distance()
    assert 0.3 <= distance <= 1.0 - 0.05 - 0.15 + 1e-6
    env.reset(seed=0, options={"start_pose": [6.0, 0.0, 0.0]})  # open corridor behind
    assert env.unwrapped._chase_distance() == pytest.approx(1.8)
    assert env.render().shape == (360, 480, 3)


def test_human_mode_without_a_display_says_so(make_env, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(RuntimeError, match="needs a display"):
        make_env(render_mode="human", camera__enabled=False)
    # not declared then, so the env checkers do not try it
    assert make_env(camera__enabled=False).metadata["render_modes"] == ["rgb_array"]


def test_unknown_view_is_named(make_env):
    with pytest.raises(ConfigError, match=r"render\.view"):
        make_env(render__view="sky")


@pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="needs xvfb-run (Debian: xvfb)")
def test_human_mode_shows_a_window_under_xvfb():
    script = """
import gymnasium as gym, numpy as np, stsf_gym
env = gym.make("stsf_gym/Straight10m-STSF-v0", render_mode="human", camera__mode="fast")
env.reset(seed=0)
steps = [env.step(np.float32([0.5, 0.0])) for _ in range(3)]
print("rendered", env.render())
env.close()
"""
    result = subprocess.run(
        ["xvfb-run", "-a", sys.executable, "-c", script],
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    assert "rendered None" in result.stdout
