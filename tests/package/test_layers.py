"""The import layers hold: the estimation core runs without the simulator, and the import graph
points one way (:mod:`stsf_gym.layers`)."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import ROOT

from stsf_gym import layers

CORE_IMPORT = """
import importlib, json, pkgutil, sys
import numpy as np
import stsf_gym.estimators, stsf_gym.fusion, stsf_gym.vision
for package in (stsf_gym.estimators, stsf_gym.fusion, stsf_gym.vision):
    for module in pkgutil.walk_packages(package.__path__, package.__name__ + "."):
        importlib.import_module(module.name)
from stsf_gym.estimators import ESTIMATORS, make_estimator
for name in ESTIMATORS:
    make_estimator(name)
print(json.dumps(sorted(sys.modules)))
"""


@pytest.mark.slow
def test_the_estimators_load_without_the_simulator():
    done = subprocess.run(
        [sys.executable, "-c", CORE_IMPORT], capture_output=True, text=True, cwd=ROOT, check=True
    )
    modules = json.loads(done.stdout)
    assert "stsf_gym.estimators.landmark_fusion" in modules  # the walk imported everything
    loaded = [m for m in modules if m.startswith(("stsf_gym.envs", "pybullet"))]
    assert not loaded, f"the estimation core loaded the simulator: {loaded}"


def test_the_import_graph_points_one_way():
    assert layers.violations() == []
    graph = layers.layer_graph(layers.module_imports())
    assert "stsf_gym.experiments" not in graph["stsf_gym.agents"]
    for core in ("stsf_gym.estimators", "stsf_gym.fusion", "stsf_gym.vision"):
        assert not graph[core] & {
            "stsf_gym.envs",
            "pybullet",
            "stsf_gym.agents",
            "stsf_gym.wrappers",
        }, core
    assert "pybullet" not in graph["stsf_gym.envs.rendering"]
    # recordings are written from any env stack and replayed with no simulator
    assert not graph["stsf_gym.recording"] & {"stsf_gym.envs", *layers.ENV_FOLDERS, "pybullet"}
    assert graph["stsf_gym.envs"] - {"pybullet", "pybullet_utils", *layers.ENV_FOLDERS} <= {
        "stsf_gym.geometry",
        "stsf_gym.vision.landmarks",
        "stsf_gym.validation",
        "stsf_gym.config_files",
        "stsf_gym.camera_model",
    }
    assert (
        "stsf_gym.envs" not in graph["stsf_gym.wrappers"]
    )  # the episode env builder joins the two


def _tree(tmp_path: Path, files: dict[str, str]) -> Path:
    for name in ("stsf_gym/__init__.py", "envs/__init__.py", "agents/__init__.py", *files):
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(files.get(name, ""))
    return tmp_path


def test_violations_are_found(tmp_path):
    root = _tree(
        tmp_path,
        {
            "stsf_gym/estimators/__init__.py": "def f():\n    import pybullet\n",
            "stsf_gym/estimators/model.py": "from stsf_gym.envs.robot import Robot\n",
            "envs/robot.py": "from stsf_gym.estimators import model\nRobot = 1\n",
            "agents/training/train.py": "from stsf_gym.experiments.runs import _private\n",
            "stsf_gym/experiments/__init__.py": "",
            "stsf_gym/experiments/runs.py": (
                "from typing import TYPE_CHECKING\n"
                "if TYPE_CHECKING:\n    from stsf_gym.cli import main\n_private = 1\n"
            ),
            "stsf_gym/newlayer.py": "",
        },
    )
    found = "\n".join(layers.violations(root))
    assert "stsf_gym.estimators imports pybullet" in found
    assert "stsf_gym.estimators.model imports stsf_gym.envs.robot" in found
    assert "stsf_gym.envs.robot imports stsf_gym.estimators.model" in found
    assert (
        "stsf_gym.agents.training.train imports stsf_gym.experiments.runs (stsf_gym.agents ->"
        in found
    )
    assert "private name stsf_gym.experiments.runs._private" in found
    assert (
        "import cycle: stsf_gym.envs.robot -> stsf_gym.estimators.model -> stsf_gym.envs.robot"
        in found
    )
    assert "stsf_gym.newlayer: layer stsf_gym.newlayer has no rule" in found  # every layer has
    assert "stsf_gym.cli" not in found  # imports for type checking only do not count


@pytest.mark.slow
def test_layers_command_prints_the_graph():
    done = subprocess.run(
        [sys.executable, "-m", "stsf_gym.layers"], capture_output=True, text=True, cwd=ROOT
    )
    assert done.returncode == 0, done.stdout
    assert re.search(
        r"stsf_gym\.wrappers +-> stsf_gym\.estimators, stsf_gym\.geometry, "
        r"stsf_gym\.validation\n",
        done.stdout,
    )
    assert done.stdout.rstrip().endswith("violations:\n  none")


def test_the_committed_picture_is_what_the_code_draws():
    """docs/reference/layers.svg is redrawn by ``python -m stsf_gym.layers --picture``."""
    committed = (ROOT / "docs" / "reference" / "layers.svg").read_text()
    assert committed == layers.picture(), (
        "the layers changed: python -m stsf_gym.layers --picture > docs/reference/layers.svg"
    )


def test_the_package_dir_mapping_is_written_once_for_the_code():
    """pyproject's package-dir, which setuptools reads, is the copy of layers.PACKAGE_DIRS."""
    tomllib = pytest.importorskip("tomllib")  # Python 3.11+
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert pyproject["tool"]["setuptools"]["package-dir"] == layers.PACKAGE_DIRS


def test_a_cycle_of_type_only_imports_is_a_cycle(tmp_path):
    root = _tree(
        tmp_path,
        {
            "envs/config.py": "from stsf_gym.envs.checks import check\n",
            "envs/checks.py": (
                "from typing import TYPE_CHECKING\n"
                "if TYPE_CHECKING:\n    from stsf_gym.envs.config import World\n"
                "def check(world: 'World'): ...\n"
            ),
        },
    )
    found = layers.violations(root)
    assert "import cycle: stsf_gym.envs.checks -> stsf_gym.envs.config -> stsf_gym.envs.checks" in (
        found
    )
    assert not [v for v in found if "is not allowed" in v]  # the rules count runtime imports


def test_a_long_module_is_refused_unless_listed_with_its_reason(tmp_path):
    long = "x = 1\n" * (layers.MODULE_LIMIT + 1)
    found = layers.violations(_tree(tmp_path, {"envs/corridor_env.py": long, "envs/big.py": long}))
    assert any(v.startswith("stsf_gym.envs.big holds 401 lines") for v in found)
    assert not any("corridor_env" in v for v in found)  # listed in LONG_MODULES, with why


def test_a_folder_names_its_idea_however_many_modules_it_holds(tmp_path):
    crowded = {f"envs/sensors/part_{k}.py": "x = 1\n" for k in range(24)}
    files = {"envs/sensors/__init__.py": '"""The robot\'s sensors."""\n', **crowded}
    files["envs/worlds/__init__.py"] = "x = 1\n"
    found = layers.violations(_tree(tmp_path, files))
    assert not any("stsf_gym.envs.sensors" in v for v in found)  # 25 modules, one idea
    assert any(v.startswith("stsf_gym.envs.worlds: its __init__ has no docstring") for v in found)
    assert layers.folder_idea(tmp_path / "envs/sensors/__init__.py") == "The robot's sensors."
