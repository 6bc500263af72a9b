"""``stsf_gym/Generated-v0``: the corridor env on a new generated world every episode.

World seeds come in three disjoint splits (``configs/generator/default.yaml``, ``splits``):
``train`` is world seeds 0 to 999,999, ``test`` 1,000,000 to 1,009,999 (the benchmark's) and
``val`` 2,000,000 to 2,009,999 (where training evaluates and selects its best model). An agent
trained on ``split="train"`` never sees a test world, and none is used to choose it.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import gymnasium as gym

from stsf_gym.config_files import merge_settings
from stsf_gym.envs.config import EnvConfig, WorldConfig, check_env_keywords, load_config
from stsf_gym.envs.corridor_env import CorridorEnv
from stsf_gym.envs.random_streams import RandomStreams
from stsf_gym.envs.worlds.generator import GenerationError, generate_world, world_tree
from stsf_gym.envs.worlds.generator_config import GeneratorConfig, load_generator_config
from stsf_gym.validation import ConfigError, reset_options

REDRAWS = 10  # drawn worlds the generator cannot lay out, skipped before the error is raised
GENERATED = "generated"  # the world name of generated worlds; ``generated:<split>`` labels


def parse_world(world) -> str | None:
    """The split of a generated-world label ``generated:<split>``, ``None`` for any other
    world (a name, a YAML path or a mapping)."""
    if not isinstance(world, str):
        return None
    name, _, split = world.partition(":")
    if name != GENERATED:
        return None
    if not split:
        raise ValueError(
            "world 'generated' needs a split: generated:train, generated:val or generated:test"
        )
    return split


def generated_label(split: str) -> str:
    """The world label of a split of generated worlds, e.g. ``generated:test``."""
    load_generator_config().split_range(split)  # a bad split name fails here
    return f"{GENERATED}:{split}"


def make_world_env(world, **kwargs: Any) -> CorridorEnv:
    """The env of ``world``: :class:`GeneratedCorridorEnv` for ``"generated"`` (``split`` in
    ``kwargs``, default train) or ``"generated:<split>"``, else :class:`CorridorEnv`."""
    if world == GENERATED:
        return GeneratedCorridorEnv(**kwargs)
    split = parse_world(world)
    if split is not None:
        return GeneratedCorridorEnv(split=split, **kwargs)
    if "generator" in kwargs:  # a suite's id: its generator draws the worlds
        raise world_argument_error(world)
    return CorridorEnv(world=world, **kwargs)


def world_argument_error(world: object) -> ConfigError:
    """The error for a ``world`` argument given to an env that draws its worlds."""
    return ConfigError(
        f"world {world!r} given to an env that draws its worlds (generated ones, a suite's by "
        "its generator); drop the world argument, or give it to stsf_gym/Corridor-v0",
        "world",
    )


def make_suite_env(env: dict, **overrides: Any) -> GeneratedCorridorEnv:
    """A suite's world env (``stsf_gym/Suite-<Name>-v0``): the suite's settings ``env`` (its
    ``generator`` and env sections) with ``overrides`` over them section by section
    (:func:`~stsf_gym.config_files.merge_settings`)."""
    return GeneratedCorridorEnv(**merge_settings(env, overrides))


def episode_world(world, seed: int, env: dict | None = None) -> WorldConfig:
    """The world an episode of ``world`` (a label, name, path or mapping) reset with ``seed``
    drives in (:func:`episode_config`)."""
    return episode_config(world, seed, env).world


def episode_config(world, seed: int, env: dict | None = None) -> EnvConfig:
    """The env config an episode of ``world`` reset with ``seed`` runs with: ``env`` as
    :func:`stsf_gym.episode_env.make_episode_env` takes it (config values, and for generated
    worlds a ``generator`` and, for ``"generated"``, a ``split``), with the episode's world."""
    settings = dict(env or {})
    config, generator = settings.pop("config", None), settings.pop("generator", None)
    split = settings.pop("split", "train") if world == GENERATED else parse_world(world)
    settings.pop("render_mode", None)
    if split is None:
        return load_config(config, world=world, **settings)
    env_cfg = load_config(config, **settings)
    gen = load_generator_config(generator)
    drawn = generate_world(world_seed_for(gen.split_range(split), seed), gen, env_cfg)
    return replace(env_cfg, world=drawn)


def world_seed_for(world_seeds: range, seed: int) -> int:
    """The world seed that ``reset(seed=seed)`` uses: the split's world ``seed`` (modulo its
    size), so episode seeds 0..N-1 give N different worlds."""
    return world_seeds[seed % len(world_seeds)]


def check_distinct_worlds(world_seeds: range, seeds: range, what: str) -> None:
    """Refuse episode ``seeds`` (given by ``what``) that run past the split ``world_seeds``:
    :func:`world_seed_for` would wrap around and drive its first worlds again, counted as
    independent episodes."""
    if seeds.stop > len(world_seeds):
        raise ConfigError(
            f"{what}: episode seeds {seeds.start}..{seeds.stop - 1} run past the split's "
            f"{len(world_seeds)} worlds; seeds from {len(world_seeds)} on would drive its first "
            "worlds again, counted as new ones"
        )


class GeneratedCorridorEnv(CorridorEnv):
    """:class:`~stsf_gym.envs.corridor_env.CorridorEnv` whose world is drawn at each reset.

    - ``reset(seed=s)``: world seed ``first + s % count`` of the split (``world_seed_for``);
    - ``reset()`` without a seed: a world seed of the split drawn from the episode's world stream;
    - ``reset(options={"world_seed": k})``: world ``k`` (it must lie in the split).

    ``env.unwrapped.world_seed`` is the current world's seed. The world is rebuilt in the
    simulator only when it changes (:meth:`CorridorEnv._build_world`).

    Args:
        split: ``"train"``, ``"val"`` or ``"test"``: which world seeds are drawn.
        generator: generator YAML path or mapping over ``configs/generator/default.yaml``.
        config, render_mode, **overrides: as for :class:`CorridorEnv` (no ``world``).
    """

    def __init__(
        self,
        split: str = "train",
        generator: str | dict | None = None,
        config: str | dict | None = None,
        render_mode: str | None = None,
        **overrides: Any,
    ) -> None:
        if "world" in overrides:
            raise world_argument_error(overrides["world"])
        named = ("split", "generator", "config", "render_mode")
        check_env_keywords(type(self).__name__, overrides, named)
        self.generator: GeneratorConfig = load_generator_config(generator)
        self.split = split
        self.world_seeds = self.generator.split_range(split)
        self.world_seed = self.world_seeds.start
        first = world_tree(self.world_seed, self.generator, load_config(config, **overrides))
        super().__init__(world=first, config=config, render_mode=render_mode, **overrides)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode in a new generated world: ``seed`` picks world ``seed`` of the split, or
        ``options["world_seed"]`` (it must lie in the split) a given one.
        """
        self.require_open("reset")
        options = reset_options(options)
        world_seed = options.pop("world_seed", None)
        gym.Env.reset(self, seed=seed)
        self.streams = RandomStreams.draw(self.np_random)
        drawn = world_seed is None and seed is None
        if world_seed is None:
            world_seed = (
                world_seed_for(self.world_seeds, seed) if seed is not None else self._draw()
            )
        elif isinstance(world_seed, bool) or world_seed not in self.world_seeds:
            first, last = self.world_seeds.start, self.world_seeds.stop - 1
            raise ValueError(
                f"options['world_seed'] must be an integer in the {self.split} split "
                f"[{first}, {last}], got {world_seed!r}"
            )
        if world_seed != self.world_seed:
            world_seed, world = self._generated(int(world_seed), redraw=drawn)
            self._build_world(world)
            self.world_seed = world_seed
        return self._start_episode(options)

    def _draw(self) -> int:
        """A world seed of the split from the episode's world stream."""
        return int(self.world_seeds[int(self.streams.world.integers(len(self.world_seeds)))])

    def _generated(self, world_seed: int, redraw: bool) -> tuple[int, WorldConfig]:
        """World ``world_seed`` and its seed. A drawn world the generator cannot lay out (a rare
        seed of a demanding suite: no layout of the landmark coverage asked) is replaced by the
        next draw, up to :data:`REDRAWS` times; a world asked for by seed raises."""
        for _ in range(REDRAWS if redraw else 0):
            try:
                return world_seed, generate_world(world_seed, self.generator, self.config)
            except GenerationError:
                world_seed = self._draw()
        return world_seed, generate_world(world_seed, self.generator, self.config)
