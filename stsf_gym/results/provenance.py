"""What made a result: the code, the packages, the resolved configuration, the seeds, the command.

Every ``results.json``, ``train.json``, model file and recording carries a :func:`provenance`
record, and every cached unit of work (an episode, a sweep cell, a Table I seed, a training
checkpoint) is stamped with a :func:`fingerprint` of the code and of its resolved configuration,
so a rerun reuses it only when both are unchanged.

The code is identified three ways: the package version, the git commit with a ``dirty`` flag
(only when the package runs from a git checkout, e.g. an editable install), and
``source_digest``, a SHA-256 over every module and package config file of the installed
package. The digest is what the caches compare: it changes with any edit, committed or not,
and is the same for a wheel and the checkout it was built from. A results file also lists the
code its run loaded (:func:`loaded_code`): each package module imported in the run's process or
in a worker that ran its jobs (workers report theirs through :func:`run_reporting_modules` and
:func:`worker_result`), and every package config, with each file's digest; so a figure is
stale only when code it ran has changed (``benchmarks/measured_blocks.py``).
"""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import importlib.util
import json
import os
import platform
import shlex
import subprocess
import sys
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

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
CODE_PACKAGES = ("stsf_gym", "stsf_gym.envs", "stsf_gym.agents", "stsf_gym.configs")
CODE_SUFFIXES = (".py", ".yaml")

T = TypeVar("T")

_command: list[str] | None = None
#: The package modules (relative paths, see :func:`loaded_modules`) workers of this run loaded.
_worker_modules: set[str] = set()
#: The package data files this run read (relative paths: a shipped agent's model).
_data_files: set[str] = set()


def set_command(argv: Sequence[str]) -> None:
    """Record the command line of this run (the CLI calls it; default ``sys.argv``)."""
    global _command
    _command = list(argv)


def command_line() -> str:
    """The command of this run, as a shell would take it."""
    return shlex.join(_command if _command is not None else sys.argv)


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
    paths (``stsf_gym/cli.py``, ``envs/simulator.py``), sorted."""
    folders = _package_folders()
    files = {getattr(module, "__file__", None) for module in list(sys.modules.values())}
    found = {_relative(Path(os.path.abspath(f)), folders) for f in files if f and f.endswith(".py")}
    return sorted(found - {None})


def run_reporting_modules(fn: Callable[..., T], *args: Any) -> tuple[T, list[str]]:
    """``fn(*args)`` in a worker process, and the package modules the worker has loaded: the
    reply its parent hands to :func:`worker_result`."""
    return fn(*args), loaded_modules()


def note_worker_modules(modules: Iterable[str]) -> None:
    """Count ``modules`` (relative paths a worker reported) as code this run loaded."""
    _worker_modules.update(modules)


def note_data_files(paths: Iterable[Path]) -> None:
    """Count the package files ``paths`` (a shipped agent's models) as code this run loaded:
    results made with other bytes there are stale."""
    folders = _package_folders()
    _data_files.update(_relative(Path(os.path.abspath(path)), folders) for path in paths)


def worker_result(reply: tuple[T, list[str]]) -> T:
    """The result in a :func:`run_reporting_modules` reply, its modules noted as this run's."""
    result, modules = reply
    note_worker_modules(modules)
    return result


def loaded_code() -> dict[str, str]:
    """``{relative path: file_digest}`` of the code this run loaded: the package modules
    imported here and in its workers, every package config (read by name at run time) and the
    package data files it read (:func:`note_data_files`)."""
    folders = _package_folders()
    configs = {
        _relative(path, folders)
        for folder in folders
        for path in folder.rglob("*.yaml")
        if "__pycache__" not in path.parts
    }
    parents = {folder.name: folder.parent for folder in folders}
    code = {}
    for path in sorted({*loaded_modules(), *_worker_modules, *configs, *_data_files} - {None}):
        parent = parents.get(path.split("/", 1)[0])
        if parent is not None and (parent / path).is_file():
            code[path] = file_digest(parent / path)
    return code


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
    """The package version, git commit and dirty flag, the source digest and the code the run
    loaded (:func:`loaded_code`)."""
    try:
        version = importlib.metadata.version("stsf-gym")
    except importlib.metadata.PackageNotFoundError:
        version = None
    return {
        "version": version,
        **git_state(),
        "source_digest": source_digest(),
        "loaded_code": loaded_code(),
    }


def _canonical(value: Any) -> Any:
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"cannot identify a {type(value).__name__} in a configuration")


def config_digest(config: Mapping[str, Any]) -> str:
    """SHA-256 (hex, 16 digits) of ``config`` as canonical JSON (sorted keys)."""
    text = json.dumps(config, sort_keys=True, default=_canonical, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def by_digest(configs: Mapping[str, Mapping[str, Any]]) -> dict[str, dict]:
    """Resolved configurations of many units (by unit name) as a provenance records them:
    each distinct one once under its :func:`config_digest`, and each unit's digest."""
    digests = {name: config_digest(config) for name, config in configs.items()}
    return {
        "configs": {digests[name]: dict(config) for name, config in configs.items()},
        "units": digests,
    }


def fingerprint(config: Mapping[str, Any] | None = None) -> dict[str, str]:
    """What a cached unit of work is reused for: the code's digest and its configuration's."""
    return {"code": source_digest(), "config": config_digest(config or {})}


def provenance(
    config: Mapping[str, Any] | None = None, seeds: Iterable[int] | None = None
) -> dict[str, Any]:
    """The record a results file carries: code, packages, Python, platform, the fully resolved
    ``config``, the ``seeds`` and the command line."""
    return {
        "stsf_gym": code_version(),
        "packages": package_versions(),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "command": command_line(),
        "seeds": sorted(set(seeds)) if seeds is not None else None,
        "config": json.loads(json.dumps(config or {}, default=_canonical)),
    }


def reference_ms() -> float:
    """Milliseconds of a fixed Python + numpy workload (best of 3): the machine's speed at the
    time of the run, so figures from runs on a busy or throttled machine can be told apart."""

    def work() -> None:
        sum(i * i for i in range(300_000))
        a = np.random.default_rng(0).standard_normal((200, 200))
        for _ in range(20):
            a = np.tanh(a @ a.T / 200)

    best = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        work()
        best = min(best, time.perf_counter() - start)
    return 1000 * best
