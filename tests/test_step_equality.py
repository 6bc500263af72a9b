"""The step's hot path, rewritten for speed, drives exactly as before: episodes recorded with
the code before the rewrite (``tests/data/step_golden.npz``) are replayed to the last bit.

Regenerate only on purpose, with the code whose behaviour is the reference::

    python tests/test_step_equality.py --write
"""

import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

GOLDEN = Path(__file__).parent / "data" / "step_golden.npz"
#: (env id, overrides, steps): the true pose with the camera off, and STSF on the fast camera;
#: each with the sonar cast through PyBullet, as the first recording was (the plane cast, a
#: change of method, is compared with it in ``test_plane_cast.py``), and with the plane cast,
#: the default since (recorded when it became the default)
BULLET_SONAR = {"sonar": {"cast": "bullet"}}
CASES = {
    "truth": (
        "stsf_gym/Suite-Corridor-Truth-v0",
        {"camera": {"enabled": False}, **BULLET_SONAR},
        300,
    ),
    "stsf": ("stsf_gym/Suite-Corridor-STSF-v0", BULLET_SONAR, 300),
    "truth, plane cast": ("stsf_gym/Suite-Corridor-Truth-v0", {"camera": {"enabled": False}}, 300),
    "stsf, plane cast": ("stsf_gym/Suite-Corridor-STSF-v0", {}, 300),
}


def record(case: str) -> dict[str, np.ndarray]:
    """The follower drives ``case``'s first test world: every step's true pose, estimate,
    covariance, sonar, encoder ticks, camera detections and reward."""
    import stsf_gym  # noqa: F401 - registers the ids
    from stsf_gym.agents.registry import make_agent

    env_id, overrides, steps = CASES[case]
    env = gym.make(env_id, **overrides)
    follower = make_agent("follower")
    obs, info = env.reset(seed=3)
    follower.begin(env)
    rows: dict[str, list] = {}
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(follower.act(obs))
        points = np.asarray(obs.get("landmark_points", np.zeros(0)), dtype=float)
        for key, value in (
            ("true_pose", info["true_pose"]),
            ("pose", obs["pose"]),
            ("pose_cov", obs["pose_cov"]),
            ("sonar", obs["sonar"]),
            ("encoders", obs["encoders"]),
            ("pan_tilt", obs["camera_pan_tilt"]),
            ("points", np.resize(points.ravel(), 32)),
            ("reward", [reward]),
        ):
            rows.setdefault(key, []).append(np.asarray(value, dtype=float).ravel())
        if terminated or truncated:
            break
    env.close()
    return {f"{case}/{key}": np.array(values) for key, values in rows.items()}


@pytest.mark.parametrize("case", list(CASES))
def test_the_same_episode_to_the_last_bit(case):
    golden = np.load(GOLDEN)
    now = record(case)
    assert set(now) == {key for key in golden.files if key.startswith(f"{case}/")}
    for key, values in now.items():
        np.testing.assert_array_equal(values, golden[key], err_msg=key)


if __name__ == "__main__" and "--write" in sys.argv:
    GOLDEN.parent.mkdir(exist_ok=True)
    np.savez_compressed(GOLDEN, **{k: v for case in CASES for k, v in record(case).items()})
    print(f"wrote {GOLDEN}")
