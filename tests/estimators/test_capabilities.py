"""The abilities some pose sources have are typed members of :class:`PoseEstimator`, each with
the plain estimator's answer, so the wrappers and a log's replay call them on any source and
never ask ``hasattr`` (:mod:`stsf_gym.estimators.base`)."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest
from helpers import ROOT

from stsf_gym.estimators import make_estimator
from stsf_gym.estimators.settings import OdometrySettings
from stsf_gym.validation import ConfigError
from stsf_gym.wrappers import TruePose, estimator_driver

#: The abilities the base declares; no module of the package may probe for them by name.
ABILITIES = ("see", "seed", "spread_prior", "confirmed", "settings", "detector")


def test_a_plain_estimator_answers_every_ability():
    odometry = make_estimator("odometry")
    assert not odometry.privileged and odometry.confirmed and odometry.detector is None
    assert odometry.seed(3) is None  # draws nothing: ignored
    assert isinstance(odometry.believed_odometry(), OdometrySettings)
    with pytest.raises(TypeError, match="not privileged"):
        odometry.see(np.zeros(3))
    with pytest.raises(ConfigError, match="unknown_start needs an estimator that localizes"):
        odometry.spread_prior()


def test_the_privileged_sources_say_so_and_skip_the_latency_history():
    assert TruePose.privileged and make_estimator("degraded-truth").privileged
    assert make_estimator("degraded-truth").believed_odometry() is None  # the default belief
    driver = estimator_driver(TruePose(), delay_s=0.2, jitter_s=0.05, control_dt=0.1)
    assert driver.history is None
    with pytest.raises(ValueError, match="needs the true pose"):
        driver.update({}, 0.1, None)


def test_each_estimator_believes_its_own_odometry_settings():
    for name in ("mcl", "stsf", "ekf"):
        estimator = make_estimator(name)
        assert estimator.believed_odometry() is estimator.settings and estimator.confirmed
    own = make_estimator("examples.complementary:ComplementaryFilter")  # settings of its own
    assert own.believed_odometry() is None  # so the odometry's defaults


def _probes(path: Path) -> list[str]:
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Call) and getattr(node.func, "id", "") in ("hasattr", "getattr"):
            name = node.args[1] if len(node.args) > 1 else None
            if isinstance(name, ast.Constant) and name.value in ABILITIES:
                found.append(f"{path.relative_to(ROOT)}:{node.lineno} {name.value}")
    return found


def test_no_module_probes_an_estimator_for_an_ability():
    files = [p for folder in ("stsf_gym", "envs", "agents") for p in (ROOT / folder).rglob("*.py")]
    cli = ROOT / "stsf_gym" / "cli"  # reads parsed arguments (``args.seed``), no estimator
    probes = [hit for path in files if not path.is_relative_to(cli) for hit in _probes(path)]
    assert probes == []
