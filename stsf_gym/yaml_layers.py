"""YAML layers of a config: files read with clear errors, merged, and flat overrides.

``configs/`` holds the defaults (``default.yaml``), the worlds (``worlds/<name>.yaml``) and the
estimator settings (``estimators/<name>.yaml``); a world or estimator file may ``extends:``
another of its folder. Errors name the file: missing, unreadable, malformed YAML (with its
line) or not a mapping.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from importlib.resources import files
from pathlib import Path
from typing import Any

import yaml

from stsf_gym.validation import ConfigError

#: The package's configs (package data: ``configs/`` of the repository, ``stsf_gym/configs`` of an
#: installed wheel). The package is installed as files, so this is a real folder.
CONFIG_DIR = Path(str(files("stsf_gym.configs")))
#: Benchmark suites (``configs/suites/<name>.yaml``, :mod:`stsf_gym.envs.suite`).
SUITE_DIR = CONFIG_DIR / "suites"


def read_yaml(path: str | Path) -> dict:
    """The mapping in YAML file ``path``; a missing, unreadable or malformed file is named."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"config file not found: {path}")
    try:
        data = yaml.safe_load(path.read_text())
    except OSError as err:
        raise ConfigError(f"cannot read config file {path}: {err.strerror}") from err
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(err, "problem", None) or str(err)
        raise ConfigError(f"malformed YAML{where}: {problem}", source=shown(path)) from err
    if not isinstance(data, dict | None):
        raise ConfigError(f"config file {path} must hold a mapping, got {type(data).__name__}")
    return data or {}


def shown(path: str | Path) -> str:
    """``path`` as errors show it: ``configs/...`` for the package's own configs."""
    path = Path(path)
    try:
        return str(Path(CONFIG_DIR.name) / path.resolve().relative_to(CONFIG_DIR.resolve()))
    except ValueError:
        return str(path)


def deep_merge(base: dict, update: Mapping) -> dict:
    """Return ``base`` updated by ``update``; nested mappings merge, anything else replaces."""
    merged = copy.deepcopy(base)
    for key, value in update.items():
        if isinstance(value, Mapping) and isinstance(merged.get(key), dict):
            merged[key] = deep_merge(merged[key], value)
        else:
            merged[key] = copy.deepcopy(value)
    return merged


def overrides_to_tree(overrides: Mapping[str, Any]) -> dict:
    """Turn flat overrides (``camera__width=640`` or ``"camera.width": 640``) into a tree."""
    tree: dict = {}
    for key, value in overrides.items():
        *parents, leaf = key.replace("__", ".").split(".")
        node = tree
        for part in parents:
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                raise ConfigError(f"override {key!r} goes inside {part!r}, which is not a mapping")
        if isinstance(value, Mapping):  # merged with keys set before, e.g. camera__control
            existing = node.get(leaf)
            value = deep_merge(existing if isinstance(existing, dict) else {}, value)
        node[leaf] = value
    return tree


def merge_settings(base: Mapping[str, Any] | None, overrides: Mapping[str, Any]) -> dict:
    """Env keyword arguments ``overrides`` over ``base`` (each flat ``camera__width`` keys or
    whole sections), section by section: ``sonar={"cast": "bullet"}`` given to a suite that
    sets ``sonar.beam`` keeps the suite's beam (a plain ``{**base, **overrides}`` drops it)."""
    return deep_merge(overrides_to_tree(dict(base or {})), overrides_to_tree(dict(overrides)))


def world_files(world: str | Path) -> list[tuple[Path, dict]]:
    """A world by name (``configs/worlds/<name>.yaml``) or YAML path, as (file, keys) layers."""
    return extended_files(world, CONFIG_DIR / "worlds", "world")


def extended_files(
    name: str | Path, folder: Path, kind: str, seen: tuple[Path, ...] = ()
) -> list[tuple[Path, dict]]:
    """A config by name (``folder/<name>.yaml``) or YAML path, as (file, keys) layers.

    A file may name another of its ``kind`` in ``extends``; its keys go over that one's (later
    layer). Unknown names list the known ones; a cycle of ``extends`` is named.
    """
    candidate = Path(name)
    if candidate.suffix not in (".yaml", ".yml"):
        candidate = folder / f"{name}.yaml"
        if not candidate.is_file():
            known = sorted(p.stem for p in folder.glob("*.yaml"))
            raise ConfigError(f"unknown {kind} {str(name)!r}; known {kind}s: {', '.join(known)}")
    if candidate.resolve() in seen:
        chain = " -> ".join(shown(p) for p in (*seen, candidate))
        raise ConfigError(f"{kind} files extend each other in a cycle: {chain}")
    data = read_yaml(candidate)
    base = data.pop("extends", None)
    if base is None:
        return [(candidate, data)]
    if not isinstance(base, str):
        raise ConfigError(f"extends must name a {kind}, got {base!r}", "extends", shown(candidate))
    return [*extended_files(base, folder, kind, (*seen, candidate.resolve())), (candidate, data)]
