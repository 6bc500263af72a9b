"""Installable like a library: the sdist builds a wheel with every module and config inside one
``stsf_gym`` namespace, and that wheel, installed (not editable) into a fresh virtual environment
with its core dependencies only (no extra's module importable there), runs the quick start and
works from a folder that holds its own ``envs`` and ``agents`` packages."""

from __future__ import annotations

import importlib.metadata
import importlib.util
import json
import subprocess
import sys
import sysconfig
import tarfile
import zipfile
from pathlib import Path

import pytest
from helpers import ROOT
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

from stsf_gym import __version__
from stsf_gym.layers import PACKAGE_DIRS

#: Repository folder -> the import package's folder in the wheel (the package-dir mapping).
FOLDERS = {folder: package.replace(".", "/") for package, folder in PACKAGE_DIRS.items()}

USER_SCRIPT = """
import json, sys
import gymnasium as gym
import numpy as np
import envs, agents  # the user's own packages, not ours
import stsf_gym
from stsf_gym.wrappers import PoseEstimateWrapper

env = PoseEstimateWrapper(gym.make("stsf_gym/Corridor-v0", camera__mode="fast"), "stsf")
obs, info = env.reset(seed=0)
for _ in range(20):
    obs, reward, terminated, truncated, info = env.step(np.array([0.5, 0.0], np.float32))
print(json.dumps({
    "user_envs": envs.MINE, "user_agents": agents.MINE,
    "stsf_gym": stsf_gym.__file__, "envs": sys.modules["stsf_gym.envs"].__file__,
    "pose": obs["pose"].tolist(), "cov_finite": bool(np.isfinite(obs["pose_cov"]).all()),
}))
"""


def _run(*args: str | Path, cwd: Path = ROOT, timeout: int = 600) -> str:
    done = subprocess.run(
        [str(a) for a in args], cwd=cwd, capture_output=True, text=True, timeout=timeout
    )
    assert done.returncode == 0, f"{args}: {done.stdout[-2000:]}\n{done.stderr[-4000:]}"
    return done.stdout


def _build(hook: str, source: Path, dist: Path) -> Path:
    """Run setuptools' PEP 517 ``hook`` (build_sdist or build_wheel) in ``source``; its output
    holds no warning (a "Package would be ignored" box per config folder read as broken)."""
    code = f"from setuptools import build_meta; print(build_meta.{hook}({str(dist)!r}))"
    command = [sys.executable, "-W", "always", "-c", code]
    done = subprocess.run(command, cwd=source, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-4000:]
    assert "Warning" not in done.stdout + done.stderr, (done.stdout + done.stderr)[-4000:]
    return dist / done.stdout.strip().splitlines()[-1]


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> dict[str, Path]:
    """The sdist of the checkout, and the wheel built from that unpacked sdist (so the sdist is
    shown complete)."""
    dist = tmp_path_factory.mktemp("dist")
    sdist = _build("build_sdist", ROOT, dist)
    with tarfile.open(sdist) as tar:
        tar.extractall(dist / "unpacked", filter="data")
    wheel = _build("build_wheel", next((dist / "unpacked").iterdir()), dist)
    return {"sdist": sdist, "wheel": wheel}


@pytest.mark.slow
def test_the_wheel_holds_one_namespace_with_every_module_and_config(built):
    names = zipfile.ZipFile(built["wheel"]).namelist()
    tops = {name.split("/")[0] for name in names}
    dist_info = built["wheel"].name.split("-")[0] + f"-{__version__}.dist-info"
    assert tops == {"stsf_gym", dist_info}, tops
    expected = {
        f"{package}/{path.relative_to(ROOT / folder).as_posix()}"
        for folder, package in FOLDERS.items()
        for path in (ROOT / folder).rglob("*.py")
        if "__pycache__" not in path.parts
    }
    expected |= {
        f"stsf_gym/configs/{path.relative_to(ROOT / 'configs').as_posix()}"
        for path in (ROOT / "configs").rglob("*")
        if path.suffix in (".yaml", ".py")
    }
    expected |= {  # the shipped agents: models, their train.json, agent.json
        f"stsf_gym/agents/{path.relative_to(ROOT / 'agents').as_posix()}"
        for path in (ROOT / "agents" / "pretrained" / "trained-models").rglob("*")
        if path.is_file()
    }
    missing = expected - set(names)
    assert not missing, f"not in the wheel: {sorted(missing)[:10]}"
    assert "stsf_gym/configs/default.yaml" in names


def test_the_sdist_holds_the_repository_folders(built):
    names = tarfile.open(built["sdist"]).getnames()
    root = names[0].split("/")[0]
    for path in ("pyproject.toml", "configs/default.yaml", "envs/corridor_env.py", "agents/zoo.py"):
        assert f"{root}/{path}" in names, path


#: Distributions a fresh virtual environment has without asking (pip's own).
VENV_OWN = {"pip", "setuptools", "wheel"}


def core_closure(wheel: Path) -> set[str]:
    """The distributions the wheel's core needs (its requirements without an extra, and
    theirs, as installed here), by canonical name."""
    dist_info = f"stsf_gym-{__version__}.dist-info"
    metadata = zipfile.ZipFile(wheel).read(f"{dist_info}/METADATA").decode()
    todo = [
        line.split(":", 1)[1] for line in metadata.splitlines() if line.startswith("Requires-Dist:")
    ]
    needed: set[str] = set()
    while todo:
        requirement = Requirement(todo.pop())
        name = canonicalize_name(requirement.name)
        if name in needed or (
            requirement.marker and not requirement.marker.evaluate({"extra": ""})
        ):
            continue
        needed.add(name)
        try:
            todo += importlib.metadata.distribution(name).requires or []
        except importlib.metadata.PackageNotFoundError:
            continue
    return needed


def extras_only_modules(wheel: Path) -> list[str]:
    """Top-level modules installed here by distributions outside the core (the extras' and the
    test tools'): a core install would not have them."""
    allowed = core_closure(wheel) | VENV_OWN | {"stsf-gym"}
    return sorted(
        module
        for module, dists in importlib.metadata.packages_distributions().items()
        if not any(canonicalize_name(d) in allowed for d in dists)
    )


@pytest.fixture(scope="module")
def installed(built, tmp_path_factory) -> Path:
    """A fresh virtual environment with the wheel installed (no editable install, no access
    to the checkout); the core dependencies come from this test's environment, read only, and
    every module only an extra or a test tool installs is made unimportable there (a core
    install: ``import mcap`` fails as if it were not installed)."""
    venv = tmp_path_factory.mktemp("venv")
    _run(sys.executable, "-m", "venv", venv)
    python = venv / "bin" / "python"
    _run(python, "-m", "pip", "install", "--quiet", "--no-deps", "--no-index", built["wheel"])
    site = _run(python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])")
    # the dependencies, appended after the venv's own site-packages (a .pth file adds a path;
    # the .pth files inside that path, such as this checkout's editable install, are not read)
    Path(site.strip(), "dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    absent = dict.fromkeys(extras_only_modules(built["wheel"]))
    Path(site.strip(), "core_only.pth").write_text(f"import sys; sys.modules.update({absent!r})\n")
    return venv


@pytest.mark.slow
def test_a_core_install_runs_the_quick_start_and_names_the_missing_extra(installed, tmp_path):
    python, cli = installed / "bin" / "python", installed / "bin" / "stsf-gym"
    for extra_module in ("mcap", "rosbags", "rerun", "ray", "rl_zoo3"):
        if importlib.util.find_spec(extra_module) is not None:  # installed here, hidden there
            done = subprocess.run([python, "-c", f"import {extra_module}"], capture_output=True)
            assert done.returncode != 0, extra_module
    args = ["evaluate", "--estimators", "odometry,stsf,ekf", "--seeds", "1", "--workers", "1"]
    args += ["--set", "camera.mode=fast", "--set", "sim.max_episode_seconds=3", "--json"]
    summary = json.loads(_run(cli, *args, "--out", tmp_path / "quick", cwd=tmp_path))
    assert [row["estimator"] for row in summary["rows"]] == ["odometry", "stsf", "ekf"]
    done = subprocess.run(
        [cli, *args, "--record", "mcap", "--out", tmp_path / "rec"], capture_output=True, text=True
    )
    assert done.returncode == 2 and "pip install 'stsf-gym[record]'" in done.stderr, done.stderr


@pytest.mark.slow
def test_the_installed_wheel_works_beside_a_users_own_envs_and_agents(installed, tmp_path):
    for package in ("envs", "agents"):
        (tmp_path / package).mkdir()
        (tmp_path / package / "__init__.py").write_text(f"MINE = {package!r}\n")
        (tmp_path / package / "corridor_env.py").write_text("raise ImportError('the user')\n")
    out = json.loads(_run(installed / "bin" / "python", "-c", USER_SCRIPT, cwd=tmp_path))
    assert (out["user_envs"], out["user_agents"]) == ("envs", "agents")
    for module in ("stsf_gym", "envs"):
        assert out[module].startswith(str(installed)), out[module]  # the wheel, not the checkout
    assert out["pose"][0] > 0 and out["cov_finite"]

    demo = tmp_path / "demo"
    args = ["demo", "--worlds", "1", "--out", demo, "--seconds", "3", "--no-video"]
    args += ["--workers", "1", "--json"]
    summary = json.loads(_run(installed / "bin" / "stsf-gym", *args, cwd=tmp_path))
    assert len(summary["rows"]) == 4
    made_by = json.loads((demo / "results.json").read_text())["provenance"]
    assert made_by["stsf_gym"]["version"] == __version__
    assert made_by["stsf_gym"]["commit"] is None  # an installed wheel is no git checkout
    assert made_by["command"].startswith("stsf-gym demo --worlds 1")
