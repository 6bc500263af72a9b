"""Which code made a result: the package version, the git commit, the source digest, the
installed packages, and the code the run loaded.

The code is identified three ways: the package version, the git commit with a ``dirty`` flag
(only when the package runs from a git checkout, e.g. an editable install), and
``source_digest``, a SHA-256 over every module and package config file of the installed
package (the same for a wheel and the checkout it was built from). A results file also lists
the code its run loaded (:func:`loaded_code`): each package module imported in the run's process
or in a worker that ran its jobs (workers report theirs through :func:`run_reporting_modules`
and :func:`worker_result`), every package config and the package data files it read
(:func:`note_data_files`), with each file's digest (the workers' modules and the data files
are kept by the run's :class:`~stsf_gym.results.run_context.RunContext`); timings, which any
rewrite may change, are judged by what that code computes (:func:`timed_code`). What a
number depends on is the behaviour versions of the subsystems the run loaded
(:mod:`stsf_gym.results.behaviour`).
"""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import importlib.util
import os
import subprocess
import sys
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any, TypeVar

from stsf_gym.layers import PACKAGE_DIRS
from stsf_gym.results.behaviour import behaviour, code_digest
from stsf_gym.results.run_context import RunContext, current_run

#: Distributions whose versions shape results (those installed are listed).
RESULT_PACKAGES = (
    "gymnasium",
    "pybullet",
    "numpy",
    "scipy",
    "opencv-python-headless",
    "moderngl",
    "stable-baselines3",
    "torch",
    "gtsam",
)
#: The import packages whose files make the code (``stsf_gym`` and the folders mapped into it).
CODE_PACKAGES = tuple(PACKAGE_DIRS)
CODE_SUFFIXES = (".py", ".yaml")

T = TypeVar("T")


def _package_folders() -> list[Path]:
    folders = []
    for name in CODE_PACKAGES:
        spec = importlib.util.find_spec(name)
        found = (spec.submodule_search_locations or []) if spec else []
        folders += [Path(os.path.abspath(p)) for p in found]
    return folders


def _relative(path: Path, folders: list[Path]) -> str | None:
    """``path`` (absolute) as ``<folder>/<inside>`` of the innermost of the package ``folders``
    holding it (the same for a checkout and a wheel), or None outside them."""
    holders = [folder for folder in folders if path.is_relative_to(folder)]
    deepest = max(holders, key=lambda folder: len(folder.parts), default=None)
    return None if deepest is None else path.relative_to(deepest.parent).as_posix()


def file_digest(path: Path) -> str:
    """SHA-256 (hex, 16 digits) of the bytes of the file ``path``."""
    return hashlib.sha256(path.read_bytes()).hexdigest()[:16]


def loaded_modules() -> list[str]:
    """The package's module files imported in this process (``sys.modules``), as relative
    paths (``stsf_gym/wrappers/estimate.py``, ``envs/simulator.py``), sorted."""
    folders = _package_folders()
    files = {getattr(module, "__file__", None) for module in list(sys.modules.values())}
    paths = (Path(os.path.abspath(f)) for f in files if f and f.endswith(".py"))
    return sorted({found for path in paths if (found := _relative(path, folders)) is not None})


def run_reporting_modules(fn: Callable[..., T], *args: Any) -> tuple[T, list[str]]:
    """``fn(*args)`` in a worker process, and the package modules the worker has loaded: the
    reply its parent hands to :func:`worker_result`."""
    return fn(*args), loaded_modules()


def note_worker_modules(modules: Iterable[str], run: RunContext | None = None) -> None:
    """Count ``modules`` (relative paths a worker reported) as code ``run`` (default the
    current one) loaded."""
    (current_run() if run is None else run).note_worker_modules(modules)


def note_data_files(paths: Iterable[Path]) -> None:
    """Count the package files ``paths`` (a shipped agent's models) as code the current run
    loaded: results made with other bytes there are stale."""
    folders = _package_folders()
    found = (_relative(Path(os.path.abspath(path)), folders) for path in paths)
    current_run().note_data_files(path for path in found if path is not None)


def worker_result(reply: tuple[T, list[str]], run: RunContext | None = None) -> T:
    """The result in a :func:`run_reporting_modules` reply, its modules noted as ``run``'s
    (default the current one)."""
    result, modules = reply
    note_worker_modules(modules, run)
    return result


def loaded_code() -> dict[str, str]:
    """``{relative path: file_digest}`` of the code the current run loaded: the package modules
    imported here and in its workers, every package config (read by name at run time) and the
    package data files it read (:func:`note_data_files`)."""
    run = current_run()
    folders = _package_folders()
    configs = {
        found
        for folder in folders
        for path in folder.rglob("*.yaml")
        if "__pycache__" not in path.parts and (found := _relative(path, folders)) is not None
    }
    parents = {folder.name: folder.parent for folder in folders}
    code = {}
    for path in sorted({*loaded_modules(), *run.worker_modules, *configs, *run.data_files}):
        parent = parents.get(path.split("/", 1)[0])
        if parent is not None and (parent / path).is_file():
            code[path] = file_digest(parent / path)
    return code


def package_file(path: str) -> Path:
    """The file of the package's relative ``path`` (``envs/robot.py``) in this installation."""
    parents = {folder.name: folder.parent for folder in _package_folders()}
    return parents[path.split("/", 1)[0]] / path


def timed_code(loaded: Mapping[str, str]) -> dict[str, str]:
    """``{relative path: code_digest}`` of the ``loaded`` code (:func:`loaded_code`): what a
    timing depends on, docstrings and comments left out (a second per hundred modules)."""
    return {path: code_digest(package_file(path)) for path in loaded}


@functools.cache
def source_digest() -> str:
    """SHA-256 (hex, 16 digits) over the relative path and bytes of every ``.py`` and ``.yaml``
    file of the package folders, in sorted order."""
    digest = hashlib.sha256()
    for folder in _package_folders():
        files = sorted(p for p in folder.rglob("*") if p.suffix in CODE_SUFFIXES)
        for path in files:
            if "__pycache__" in path.parts:
                continue
            digest.update(str(path.relative_to(folder.parent)).encode() + b"\0")
            digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def _git(*args: str, cwd: Path) -> str | None:
    try:
        done = subprocess.run(
            ["git", *args], cwd=cwd, capture_output=True, text=True, timeout=10, check=True
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout.strip()


@functools.cache
def git_state() -> dict[str, Any]:
    """``{"commit", "dirty"}`` of the checkout the package runs from; both ``None`` when it is
    not a git checkout (an installed wheel: its files are not tracked by any repository)."""
    here = Path(__file__).resolve().parent
    if _git("ls-files", "--error-unmatch", "__init__.py", cwd=here) is None:
        return {"commit": None, "dirty": None}
    commit = _git("rev-parse", "HEAD", cwd=here)
    status = _git("status", "--porcelain", "--untracked-files=no", cwd=here)
    return {"commit": commit, "dirty": bool(status) if status is not None else None}


def package_versions(names: Iterable[str] = RESULT_PACKAGES) -> dict[str, str]:
    """Installed versions of ``names`` (those not installed are left out)."""
    versions = {}
    for name in names:
        try:
            versions[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            continue
    return versions


def code_version() -> dict[str, Any]:
    """The package version, git commit and dirty flag, the source digest, the code the run
    loaded (:func:`loaded_code`) and the behaviour versions of its subsystems."""
    try:
        version = importlib.metadata.version("stsf-gym")
    except importlib.metadata.PackageNotFoundError:
        version = None
    loaded = loaded_code()
    return {
        "version": version,
        **git_state(),
        "source_digest": source_digest(),
        "behaviour": behaviour(loaded),
        "loaded_code": loaded,
    }
