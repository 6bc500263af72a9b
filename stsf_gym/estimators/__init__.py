"""Pose estimators behind one interface (:class:`PoseEstimator`), chosen by name.

Options come from ``configs/estimators/<name>.yaml`` (when present) and keyword arguments.
"""

from __future__ import annotations

import importlib
import inspect

from envs.config import CONFIG_DIR, ConfigError, read_yaml
from stsf_gym.estimators.base import MapLandmark, PoseEstimator, SensorModel

#: Estimators by name: "module:class", imported when first made.
ESTIMATORS: dict[str, str] = {
    "odometry": "stsf_gym.estimators.dead_reckoning:OdometryEstimator",
    "conventional": "stsf_gym.estimators.landmark_fusion:ConventionalEstimator",
    "stsf": "stsf_gym.estimators.landmark_fusion:STSFEstimator",
    "ekf": "stsf_gym.estimators.ekf:EKFEstimator",
}
#: Privileged pose sources built like estimators but handed the true pose (``see``) by the
#: wrapper: for the accuracy curve only, never a real estimator.
PRIVILEGED: dict[str, str] = {
    "degraded-truth": "stsf_gym.estimators.degraded_truth:DegradedTruth",
}

__all__ = [
    "ESTIMATORS",
    "PRIVILEGED",
    "MapLandmark",
    "PoseEstimator",
    "SensorModel",
    "make_estimator",
]


def make_estimator(name: str, **options) -> PoseEstimator:
    """A fresh estimator ``name`` with options from its YAML file overridden by ``options``."""
    known = {**ESTIMATORS, **PRIVILEGED}
    if name not in known:
        raise ValueError(f"unknown estimator {name!r}; known: {', '.join(sorted(known))}")
    module, _, class_name = known[name].partition(":")
    cls = getattr(importlib.import_module(module), class_name)
    path = CONFIG_DIR / "estimators" / f"{name}.yaml"
    merged = {**(read_yaml(path) if path.is_file() else {}), **options}
    known = _options(cls)
    unknown = sorted(set(merged) - known)
    if unknown:
        raise ConfigError(
            f"unknown option {name}.{unknown[0]}; known: {', '.join(sorted(known)) or 'none'}"
        )
    return cls(**merged)


def _options(cls: type) -> set[str]:
    """Keyword options of ``cls.__init__``, following ``**options`` up to the base classes."""
    known: set[str] = set()
    for klass in cls.__mro__:
        if "__init__" not in vars(klass):
            continue
        parameters = inspect.signature(klass.__init__).parameters.values()
        known |= {p.name for p in parameters if p.kind == p.POSITIONAL_OR_KEYWORD} - {"self"}
        if not any(p.kind == p.VAR_KEYWORD for p in parameters):
            break
    return known
