"""The proof that a change kept behaviour: episodes recorded with the reference code
(``tests/behaviour/data/step_golden.npz``) are replayed to the last bit, the world, the
estimators and the follower driving. The goldens record the behaviour versions they were made under
(:mod:`stsf_gym.results.behaviour`): a change that moves a number bumps a version, and only
then can new goldens be written::

    python tests/behaviour/test_step_equality.py --write
"""

import json
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from stsf_gym.results.behaviour import VERSIONS

GOLDEN = Path(__file__).parent / "data" / "step_golden.npz"
#: The subsystems whose behaviour the goldens pin.
PINNED = ("world", "estimation", "follower")
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


def pinned_versions() -> dict[str, int]:
    """The versions of the :data:`PINNED` subsystems now."""
    return {name: VERSIONS[name] for name in PINNED}


def golden_versions() -> dict[str, int]:
    """The versions the goldens were recorded under."""
    return json.loads(str(np.load(GOLDEN)["versions"]))


def test_the_goldens_are_of_the_versions_now():
    """A version bumped without new goldens (or goldens written without a bump) is caught."""
    assert golden_versions() == pinned_versions()


@pytest.mark.parametrize("case", list(CASES))
def test_the_same_episode_to_the_last_bit(case):
    golden = np.load(GOLDEN)
    now = record(case)
    assert set(now) == {key for key in golden.files if key.startswith(f"{case}/")}
    for key, values in now.items():
        np.testing.assert_array_equal(values, golden[key], err_msg=key)


def write() -> None:
    """New goldens, refused when they differ from the old under the same versions."""
    traces = {k: v for case in CASES for k, v in record(case).items()}
    if GOLDEN.is_file() and golden_versions() == pinned_versions():
        old = np.load(GOLDEN)
        moved = [k for k in traces if k not in old.files or not np.array_equal(traces[k], old[k])]
        if moved:
            raise SystemExit(
                f"behaviour changed ({', '.join(moved[:3])}, ...) under the same versions "
                f"{pinned_versions()}: bump the subsystem's version in "
                "stsf_gym/results/behaviour.py, then write again"
            )
    GOLDEN.parent.mkdir(exist_ok=True)
    np.savez_compressed(GOLDEN, versions=json.dumps(pinned_versions()), **traces)
    print(f"wrote {GOLDEN}")


if __name__ == "__main__" and "--write" in sys.argv:
    write()
