"""The env of an episode, built in one place: for the registered estimating ids
(``stsf_gym/Corridor-STSF-v0``, ...), for training and for evaluation alike."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import gymnasium as gym

from stsf_gym.wrappers import PoseEstimateWrapper


def make_episode_env(
    world: str | Mapping = "irl_corridor",
    estimator: str = "odometry",
    env: Mapping[str, Any] | None = None,
    estimator_options: Mapping[str, Any] | None = None,
    **overrides: Any,
) -> gym.Env:
    """``world`` (a name, YAML path or mapping; ``"generated"`` with a ``split`` override, or
    ``"generated:<split>"``: a generated world per episode) with the pan camera (pointed by the
    wrapper, so the action stays ``[v, w]``), the env settings ``env`` and ``overrides``
    (``config``, ``render_mode``, ``camera__width``, ...; see
    :class:`stsf_gym.envs.corridor_env.CorridorEnv`), wrapped in :class:`PoseEstimateWrapper` for
    the pose source ``estimator`` with ``estimator_options`` over its YAML settings."""
    from stsf_gym.envs.generated_env import make_world_env

    corridor = make_world_env(world, **{"camera__control": "pan", **(env or {}), **overrides})
    try:
        return PoseEstimateWrapper(corridor, estimator, **(estimator_options or {}))
    except Exception:
        corridor.close()
        raise
