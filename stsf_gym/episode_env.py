"""The env of an episode, built in one place: for the registered estimating ids
(``stsf_gym/Corridor-STSF-v0``, ...), for training and for evaluation alike."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict
from typing import Any

import gymnasium as gym

from stsf_gym.config_files import merge_settings
from stsf_gym.estimators import estimator_class, estimator_settings
from stsf_gym.wrappers import TRUTH, CameraPointingWrapper, PoseEstimateWrapper, check_sensors

#: Keyword arguments of an env that are not config values.
NOT_CONFIG = ("render_mode", "split", "generator")
#: What an episode's env has unless its settings say otherwise: the pan camera, which
#: :class:`CameraPointingWrapper` points, so the agent's action stays ``[v, w]``.
EPISODE_DEFAULTS = {"camera__control": "pan"}


def episode_settings(env: Mapping[str, Any] | None) -> dict[str, Any]:
    """The env settings of an episode: ``env`` over :data:`EPISODE_DEFAULTS`."""
    return {**EPISODE_DEFAULTS, **(env or {})}


def make_episode_env(
    world: str | Mapping = "irl_corridor",
    estimator: str = "odometry",
    env: Mapping[str, Any] | None = None,
    estimator_options: Mapping[str, Any] | None = None,
    **overrides: Any,
) -> gym.Env:
    """``world`` (a name, YAML path or mapping; ``"generated"`` with a ``split`` override, or
    ``"generated:<split>"``: a generated world per episode) with the settings of
    :func:`episode_settings` (``env``: the pan camera unless it says otherwise) and
    ``overrides`` (``config``, ``render_mode``, ``camera__width``, ...; see
    :class:`stsf_gym.envs.corridor_env.CorridorEnv`), wrapped in :class:`PoseEstimateWrapper` for
    the pose source ``estimator`` with ``estimator_options`` over its YAML settings, and, with a
    pan camera, in :class:`CameraPointingWrapper` (outermost: ``searching`` is its; read the
    estimate wrapper's attributes with ``get_wrapper_attr``, e.g. ``"estimator"``)."""
    from stsf_gym.envs.generated_env import make_world_env

    corridor = make_world_env(world, **merge_settings(episode_settings(env), overrides))
    try:
        estimating = PoseEstimateWrapper(corridor, estimator, **(estimator_options or {}))
        if corridor.unwrapped.config.camera.control != "pan":
            return estimating
        return CameraPointingWrapper(estimating)
    except Exception:
        corridor.close()
        raise


def estimator_options(source: str, **options: Any) -> dict:
    """The settings of pose source ``source`` (its ``configs/estimators/`` YAML with
    ``options`` over it) as plain values; ``truth`` has none."""
    return {} if source == TRUTH else asdict(estimator_settings(source, **options))


def resolved_config(
    world: str | Mapping = "irl_corridor",
    estimator: str = "odometry",
    env: Mapping[str, Any] | None = None,
    options: Mapping[str, Any] | None = None,
) -> dict:
    """Every value the env of :func:`make_episode_env` with these arguments runs with: the env
    config after all its layers (defaults, world, config file, overrides), for generated worlds
    the generator's settings and split instead of one world, and the pose source's settings
    with ``options`` over them.
    Nothing is built: the YAML layers are read and checked."""
    from stsf_gym.envs.config import load_config
    from stsf_gym.envs.generated_env import GENERATED, parse_world
    from stsf_gym.envs.worlds.generator_config import load_generator_config

    overrides = episode_settings(env)
    config = overrides.pop("config", None)
    split = overrides.get("split", "train") if world == GENERATED else parse_world(world)
    generator = overrides.get("generator")
    overrides = {k: v for k, v in overrides.items() if k not in NOT_CONFIG}
    resolved: dict[str, Any] = {}
    if split is None:
        resolved["env"] = asdict(load_config(config, world=world, **overrides))
    else:
        env_cfg = asdict(load_config(config, **overrides))
        env_cfg.pop("world")
        resolved["env"] = env_cfg
        resolved["generator"] = asdict(load_generator_config(generator))
        resolved["split"] = split
    camera = resolved["env"]["camera"]["enabled"]
    check_sensors(
        estimator, () if estimator == TRUTH else estimator_class(estimator).sensors, camera
    )
    resolved["estimator"] = {
        "name": estimator,
        "settings": estimator_options(estimator, **(options or {})),
    }
    return resolved
