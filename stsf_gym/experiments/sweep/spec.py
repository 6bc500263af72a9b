"""A sweep file, read and checked: the grid of evaluation or training cells it describes.

A sweep file (``configs/sweeps/<name>.yaml``) holds:

- ``base``: what every cell starts from: ``kind`` (``evaluate``, the default, or ``train``),
  ``world`` (irl_corridor) or ``suite`` (a benchmark suite: its test worlds and its env, with
  ``base.env`` over it), ``agent`` (follower), ``estimator``, ``seed`` (0), ``faults``
  (a fault set: ``configs/faults/<name>.yaml`` or a fault file; ``none``), ``env`` (overrides
  merged over ``configs/default.yaml``), for evaluate cells ``options`` (estimator options over
  ``configs/estimators/``) and, for training cells, ``train``.
- ``grid``: keys mapped to lists of values; every combination is a cell. Keys: ``estimator``,
  ``agent``, ``world``, ``faults``, ``seed`` (a list) or ``seeds`` (a count, from the base
  seed on), and dotted ``env.<section>.<key>`` (any env config key: the TRUE noise),
  ``options.<key>`` (an estimator option, e.g. the BELIEVED noise ``options.radius_error_std``
  of ``configs/estimators/odometry.yaml``; evaluate cells) or ``train.<key>``.
- ``one_at_a_time`` (optional): keys like ``grid``'s, each swept on its own while the others
  keep their base value, every value crossed with the whole grid (two one-dimensional noise
  studies instead of their full product).

Each cell is a job of :data:`~stsf_gym.experiments.jobs.cells.CELL_JOBS`; the sweep is named
after its file (:mod:`stsf_gym.experiments.sweep.run` runs it).
"""

from __future__ import annotations

import itertools
import json
from dataclasses import dataclass
from pathlib import Path

from stsf_gym.agents.registry import make_agent
from stsf_gym.config_files import deep_merge
from stsf_gym.envs.config import CONFIG_DIR, load_config, overrides_to_tree, read_yaml
from stsf_gym.envs.generated_env import generated_label, parse_world
from stsf_gym.envs.worlds.generator_config import load_generator_config
from stsf_gym.episode_env import estimator_options
from stsf_gym.experiments.jobs.cells import cell_kind
from stsf_gym.validation import ConfigError

FILE_KEYS = ("base", "grid", "one_at_a_time")
BASE_DEFAULTS = {
    "kind": "evaluate",
    "world": "irl_corridor",
    "agent": "follower",
    "seed": 0,
    "faults": "none",
}
PLAIN_KEYS = ("estimator", "agent", "world", "seed", "faults")
SECTIONS = {"evaluate": ("env", "options"), "train": ("env", "train")}


@dataclass(frozen=True)
class Sweep:
    """A checked sweep file: its name, path, cell kind and every cell of its grid."""

    name: str
    path: Path
    kind: str
    cells: list[dict]


def load_sweep(path: str | Path, seed: int = 0, env: dict | None = None) -> Sweep:
    """Read and check a sweep file; ``seed`` is added to every cell's seed and ``env`` merged
    into ``base.env``. Any bad key or value raises ConfigError naming the file and the key."""
    path = Path(path)
    data = read_yaml(path)
    _check_keys(path, "", data, FILE_KEYS)
    base = {**BASE_DEFAULTS, **_mapping(path, data, "base")}
    kind = base["kind"]
    try:
        cell_kind(kind)
    except ConfigError as err:
        raise ConfigError(f"{path}: base.kind: {err}") from err
    sections = SECTIONS.get(kind, ("env",))
    _check_keys(path, "base.", base, ("kind", "suite", *PLAIN_KEYS, *sections))
    for section in sections:
        base[section] = _mapping(path, base, section, f"base.{section}")
    if "suite" in base:  # a suite's test worlds and task, base.env over the suite's env
        suite = _suite(path, base.pop("suite"))
        base["world"] = generated_label("test")
        base["env"] = deep_merge(suite.episode_env, base["env"])
    base["env"] = deep_merge(base["env"], env or {})
    _checked(path, "base", base, {}, sections)
    grid = _axes(path, "grid", _mapping(path, data, "grid"), base, sections)
    single = _axes(path, "one_at_a_time", _mapping(path, data, "one_at_a_time"), base, sections)
    if "estimator" not in base and "estimator" not in grid:
        raise ConfigError(f"{path}: no estimator: set base.estimator or grid.estimator")
    if shared := sorted(grid.keys() & single.keys()):
        raise ConfigError(f"{path}: {shared[0]!r} is swept in both grid and one_at_a_time")
    points = _points(grid, single)
    cells = []
    for point in points:
        try:
            cells.append(_cell(base, point, sections, seed))
        except ConfigError as err:  # an estimator option swept over estimators of the grid
            raise ConfigError(f"{path}: cell {json.dumps(point)}: {err}") from err
    check = cell_kind(kind).check
    for cell in cells if check else []:
        try:
            check(cell)
        except ConfigError as err:
            raise ConfigError(f"{path}: cell {json.dumps(cell['values'])}: {err}") from err
    return Sweep(path.stem, path, kind, cells)


def _mapping(path: Path, data: dict, key: str, label: str = "") -> dict:
    value = data.get(key) or {}
    if not isinstance(value, dict):
        raise ConfigError(f"{path}: {label or key} must be a mapping, got {value!r}")
    return value


def _check_keys(path: Path, prefix: str, data: dict, known: tuple[str, ...]) -> None:
    unknown = [key for key in data if key not in known]
    if unknown:
        raise ConfigError(f"{path}: unknown key {prefix + unknown[0]!r}; known: {', '.join(known)}")


def _axes(path: Path, where: str, axes: dict, base: dict, sections: tuple[str, ...]) -> dict:
    """Swept keys and their values, each value checked on its own against the base."""
    checked = {}
    for key, values in axes.items():
        label = f"{where}.{key}"
        if key == "seeds":
            if isinstance(values, bool) or not isinstance(values, int) or values < 1:
                raise ConfigError(f"{path}: {label} must be a positive count, got {values!r}")
            key, values = "seed", list(range(base["seed"], base["seed"] + values))
        section = key.partition(".")[0]
        if key not in PLAIN_KEYS and not (section in sections and "." in key):
            allowed = [*PLAIN_KEYS, "seeds", *(f"{s}.<key>" for s in sections)]
            raise ConfigError(f"{path}: unknown key {label!r}; known: {', '.join(allowed)}")
        if key in checked:
            raise ConfigError(f"{path}: {label} repeats {key!r}")
        if not isinstance(values, list) or not values:
            raise ConfigError(f"{path}: {label} must be a non-empty list, got {values!r}")
        if len({json.dumps(value, sort_keys=True) for value in values}) < len(values):
            raise ConfigError(f"{path}: {label} repeats a value: {values!r}")
        for value in values:
            _checked(path, label, base, {key: value}, sections)
        checked[key] = values
    return checked


def _checked(path: Path, label: str, base: dict, point: dict, sections: tuple[str, ...]) -> None:
    """``base`` with ``point`` set must be a valid cell: estimator, seed, agent, fault set,
    and the world and env as the env builds them."""
    from stsf_gym.wrappers import check_pose_source

    try:
        cell = _apply(base, point, sections)
        estimator, seed, agent = cell["estimator"], cell["seed"], cell["agent"]
        if estimator is not None:
            check_pose_source(estimator)
        if isinstance(seed, bool) or not isinstance(seed, int):
            raise ConfigError(f"seed must be an integer, got {seed!r}")
        if not isinstance(agent, str):
            raise ConfigError(f"agent must be an agent's name or a model file, got {agent!r}")
        make_agent(agent)  # an unknown name or a missing model fails here
        _check_env(cell["env"], cell["world"])
        if cell.get("options") and estimator is not None:
            estimator_options(estimator, **cell["options"])
    except ConfigError as err:
        raise ConfigError(f"{path}: {label}: {err}") from err


def _suite(path: Path, name: object):
    from stsf_gym.envs.suite import load_suite

    try:
        return load_suite(str(name))
    except ConfigError as err:
        raise ConfigError(f"{path}: base.suite: {err}") from err


def _check_env(env: dict, world: str) -> None:
    """The env as the episode builds it; for generated worlds the generator's settings too."""
    if parse_world(world) is None:
        load_config(env, world=world)
        return
    load_generator_config(env.get("generator"))
    load_config({k: v for k, v in env.items() if k not in ("generator", "split")})


def _points(grid: dict, single: dict) -> list[dict]:
    """Swept values of every cell: the grid's product, crossed with each one-at-a-time value."""
    crossed = [dict(zip(grid, values, strict=True)) for values in itertools.product(*grid.values())]
    singles = [{key: value} for key, values in single.items() for value in values] or [{}]
    return [{**point, **one} for point in crossed for one in singles]


def _apply(base: dict, point: dict, sections: tuple[str, ...]) -> dict:
    """``base`` with the swept ``point`` set: dotted keys go into their section."""
    cell = {key: base.get(key) for key in ("kind", *PLAIN_KEYS)}
    cell.update({section: base[section] for section in sections})
    for key, value in point.items():
        section, _, rest = key.partition(".")
        if rest:
            cell[section] = deep_merge(cell[section], overrides_to_tree({rest: value}))
        else:
            cell[key] = value
    for key, suffixes in (("world", (".yaml", ".yml")), ("agent", (".zip",))):
        if isinstance(cell[key], str) and Path(cell[key]).suffix in suffixes:
            cell[key] = str(Path(cell[key]).resolve())  # Ray workers have another cwd
    if cell["faults"] != "none":
        faults = _fault_set(cell["faults"], cell["world"], cell["env"])
        cell["env"] = {**cell["env"], "faults": faults}
    return cell


def _fault_set(name: object, world: str, env: dict) -> list[dict]:
    """The ``faults`` list of fault set ``name`` (in ``configs/faults/``) or a fault file,
    checked against the world and env it will run in."""
    from stsf_gym.experiments.fault_runs import load_fault_set

    folder = CONFIG_DIR / "faults"
    path = Path(str(name))
    if path.suffix not in (".yaml", ".yml"):
        path = folder / f"{name}.yaml"
        if not path.is_file():
            known = ", ".join(sorted(p.stem for p in folder.glob("*.yaml")))
            raise ConfigError(f"unknown fault set {name!r}; known: none, {known}")
    return load_fault_set(path, world, env)[1]


def _cell(base: dict, point: dict, sections: tuple[str, ...], seed_offset: int) -> dict:
    cell = _apply(base, point, sections)
    cell["seed"] += seed_offset
    values = {**point, "seed": cell["seed"]} if "seed" in point else point
    options = estimator_options(cell["estimator"], **cell.get("options", {}))
    return {**cell, "options": options, "values": values}
