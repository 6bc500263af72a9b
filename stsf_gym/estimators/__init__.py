"""Pose estimators behind one interface (:class:`PoseEstimator`), chosen by name.

Options come from ``configs/estimators/<name>.yaml`` (when present) and keyword arguments.
"""

from __future__ import annotations

import inspect

from envs.config import CONFIG_DIR, ConfigError, read_yaml
from stsf_gym.estimators.base import MapLandmark, PoseEstimator, SensorModel
from stsf_gym.estimators.dead_reckoning import OdometryEstimator

#: Estimators by name.
ESTIMATORS: dict[str, type[PoseEstimator]] = {"odometry": OdometryEstimator}

__all__ = ["ESTIMATORS", "MapLandmark", "PoseEstimator", "SensorModel", "make_estimator"]


def make_estimator(name: str, **options) -> PoseEstimator:
    """A fresh estimator ``name`` with options from its YAML file overridden by ``options``."""
    if name not in ESTIMATORS:
        raise ValueError(f"unknown estimator {name!r}; known: {', '.join(sorted(ESTIMATORS))}")
    cls = ESTIMATORS[name]
    path = CONFIG_DIR / "estimators" / f"{name}.yaml"
    merged = {**(read_yaml(path) if path.is_file() else {}), **options}
    known = set(inspect.signature(cls.__init__).parameters) - {"self"}
    unknown = sorted(set(merged) - known)
    if unknown:
        raise ConfigError(
            f"unknown option {name}.{unknown[0]}; known: {', '.join(sorted(known)) or 'none'}"
        )
    return cls(**merged)
