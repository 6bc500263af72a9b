"""Benchmark suites: named difficulty levels of generated worlds under the declared-stop task.

A suite is ``configs/suites/<name>.yaml``: ``generator`` (over ``configs/generator/default.yaml``)
and ``env`` (over ``configs/default.yaml``: the task, the fast sensor mode, the time limit), each
value with its physical reason beside it. Its worlds are the generator's train and test splits
(:mod:`stsf_gym.envs.generated_env`). Registered ids: ``stsf_gym/Suite-<Level>-v0`` and one per
pose source, ``stsf_gym/Suite-<Level>-<Estimator>-v0`` (e.g. ``stsf_gym/Suite-Sparse-STSF-v0``);
``gym.make(id, split="test")`` gives the held-out worlds.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from stsf_gym.config_files import SUITE_DIR, read_yaml, shown
from stsf_gym.envs.config import load_config
from stsf_gym.envs.worlds.generator_config import GeneratorConfig, load_generator_config
from stsf_gym.validation import ConfigError

SUITE_KEYS = ("generator", "env")
PROTOCOL = "declare"  # every suite's task: success judged at the declared stops


def suite_names() -> list[str]:
    """The suites in ``configs/suites/`` (sorted by name): the ``--suite`` choices."""
    return [path.stem for path in sorted(SUITE_DIR.glob("*.yaml"))]


@dataclass(frozen=True)
class Suite:
    """A benchmark suite (``configs/suites/<name>.yaml``): generator and env settings over the
    defaults.
    """

    name: str
    generator: dict  # over configs/generator/default.yaml
    env: dict  # over configs/default.yaml

    @property
    def episode_env(self) -> dict:
        """The ``env`` of an episode of this suite (:func:`stsf_gym.episode_env.make_episode_env`
        with world ``generated:<split>``): the env sections and the generator."""
        return {**self.env, "generator": self.generator}

    def generator_config(self) -> GeneratorConfig:
        """The suite's generator settings, checked."""
        return load_generator_config(self.generator)


def load_suite(name: str | Path, check: bool = True) -> Suite:
    """Suite ``name`` (a name in ``configs/suites/`` or a YAML path); with ``check`` an unknown
    key, a bad generator or env value fails naming the file and the key."""
    path = Path(name)
    if not path.suffix:
        path = SUITE_DIR / f"{name}.yaml"
        if not path.is_file():
            raise ConfigError(f"unknown suite {name!r}; known: {', '.join(suite_names())}")
    data = read_yaml(path)
    unknown = sorted(set(data) - set(SUITE_KEYS))
    if unknown:
        message = f"unknown key(s) {unknown}; a suite has {list(SUITE_KEYS)}"
        raise ConfigError(message, None, shown(path))
    missing = [key for key in SUITE_KEYS if not data.get(key)]
    if missing:  # without them it would run as plain generated worlds, not as this suite
        message = f"a suite sets {list(SUITE_KEYS)}; missing or empty: {missing}"
        raise ConfigError(message, missing[0], shown(path))
    suite = Suite(path.stem, dict(data["generator"]), dict(data["env"]))
    if not check:
        return suite
    try:
        suite.generator_config()
        protocol = load_config(suite.env).task.protocol
    except ConfigError as err:
        raise ConfigError(err.message, err.key, shown(path)) from err
    if protocol != PROTOCOL:
        message = f"env.task.protocol must be {PROTOCOL!r} (a suite is judged at declared stops)"
        raise ConfigError(f"{message}, got {protocol!r}", "env.task.protocol", shown(path))
    return suite
