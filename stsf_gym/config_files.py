"""YAML layers of a config: files read with clear errors, merged, and flat overrides.

``configs/`` holds the defaults (``default.yaml``), the worlds (``worlds/<name>.yaml``) and the
estimator settings (``estimators/<name>.yaml``); a world or estimator file may ``extends:``
another of its folder. Errors name the file: missing, a folder, unreadable, over
:data:`MAX_CONFIG_BYTES`, malformed YAML (with its line) or not a mapping.

Files and ``--set`` values are read by :class:`ConfigLoader`, PyYAML's safe loader with three
changes: a number with an exponent and no dot (``1e-4``) is a number, as in YAML 1.2 (YAML 1.1
reads it as a string); a key written twice in one mapping is refused (YAML keeps the second
silently); anchors and aliases are refused (an alias bomb expands a few lines into gigabytes).
"""

from __future__ import annotations

import copy
import re
from collections.abc import Mapping
from importlib.resources import files
from pathlib import Path
from typing import Any

import yaml

from stsf_gym.validation import ConfigError, did_you_mean

#: The package's configs (package data: ``configs/`` of the repository, ``stsf_gym/configs`` of an
#: installed wheel). The package is installed as files, so this is a real folder.
CONFIG_DIR = Path(str(files("stsf_gym.configs")))
#: Benchmark suites (``configs/suites/<name>.yaml``, :mod:`stsf_gym.envs.suite`).
SUITE_DIR = CONFIG_DIR / "suites"
#: bytes: the most a config file may hold (the largest of ``configs/`` holds 9 kB; a generated
#: world a few kB): a bigger file is refused before PyYAML spends minutes and gigabytes on it.
MAX_CONFIG_BYTES = 1_000_000


class RefusedYaml(yaml.MarkedYAMLError):
    """Valid YAML that a config may not hold: a key written twice, an anchor or an alias."""


class ConfigLoader(yaml.SafeLoader):
    """The safe loader with YAML 1.2 exponent numbers, and no duplicate keys or aliases."""

    def compose_node(self, parent, index):
        """A node; an alias (``*name``) or anchor (``&name``) refused at its line."""
        event = self.peek_event()
        if isinstance(event, yaml.AliasEvent) or getattr(event, "anchor", None):
            raise RefusedYaml(
                problem="config files take no YAML anchors or aliases (&name, *name): write "
                "the value out",
                problem_mark=event.start_mark,
            )
        return super().compose_node(parent, index)

    def construct_mapping(self, node, deep=False):
        """A mapping; a key written twice refused, naming both lines."""
        seen: dict = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            if isinstance(key, str | int | float | bool) and key in seen:
                raise RefusedYaml(
                    problem=f"key {key!r} is written twice (first at line {seen[key] + 1}); "
                    "YAML would keep only the second: merge the two",
                    problem_mark=key_node.start_mark,
                )
            seen[key] = key_node.start_mark.line
        return super().construct_mapping(node, deep)


#: A number with an exponent (``1e-4``, ``2E6``, ``1.5e3``): YAML 1.1 reads one without a dot,
#: or with an unsigned exponent, as a string; YAML 1.2 and Python read numbers.
EXPONENT_NUMBER = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$")
ConfigLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float", EXPONENT_NUMBER, list("-+.0123456789")
)


def load_value(text: str) -> Any:
    """``text`` (a ``--set`` value, a file's content) parsed by :class:`ConfigLoader`."""
    return yaml.load(text, Loader=ConfigLoader)


def read_yaml(path: str | Path) -> dict:
    """The mapping in YAML file ``path``; a missing, unreadable, oversized or malformed file,
    or a folder, is named."""
    path = Path(path)
    if path.is_dir():
        raise ConfigError(f"config file {path} is a folder; give a YAML file")
    if not path.is_file():
        raise ConfigError(f"config file not found: {path}")
    try:
        size = path.stat().st_size
        if size > MAX_CONFIG_BYTES:
            raise ConfigError(
                f"config file {path} holds {size / 1e6:.1f} MB, more than a config may "
                f"({MAX_CONFIG_BYTES / 1e6:g} MB)"
            )
        data = load_value(path.read_text())
    except OSError as err:
        raise ConfigError(f"cannot read config file {path}: {err.strerror}") from err
    except RefusedYaml as err:
        mark = err.problem_mark
        where = f"line {mark.line + 1}, column {mark.column + 1}"
        raise ConfigError(f"{where}: {err.problem}", source=shown(path)) from err
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
            raise ConfigError(
                f"unknown {kind} {str(name)!r}{did_you_mean(str(name), known)}; known {kind}s: "
                f"{', '.join(known)}"
            )
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
