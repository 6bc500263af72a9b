"""Pose estimators behind one interface (:class:`PoseEstimator`), chosen by name.

Settings are frozen dataclasses (:mod:`stsf_gym.estimators.settings`) whose defaults live in
``configs/estimators/<name>.yaml`` only; keyword options go over them. This package never
imports the simulator (``envs``) or PyBullet: a :class:`SensorModel` is all it knows of a
robot, so it runs on logged data as well (:mod:`stsf_gym.wrappers` builds the model from an
env).
"""

from __future__ import annotations

import importlib

from stsf_gym.estimators.base import MapLandmark, PoseEstimator, SensorModel
from stsf_gym.estimators.settings import load_settings

#: Estimators by name: "module:class", imported when first made. ``conventional`` is the
#: paper's (the pose from the current two frames only), ``conventional-filter`` the same pair
#: measurement merged with the odometry prediction.
ESTIMATORS: dict[str, str] = {
    "odometry": "stsf_gym.estimators.dead_reckoning:OdometryEstimator",
    "conventional": "stsf_gym.estimators.conventional:ConventionalEstimator",
    "conventional-filter": "stsf_gym.estimators.landmark_fusion:ConventionalFilterEstimator",
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
    "estimator_settings",
    "make_estimator",
]


def estimator_class(name: str) -> type[PoseEstimator]:
    """The class of estimator (or privileged source) ``name``; an unknown name lists the
    known ones."""
    known = {**ESTIMATORS, **PRIVILEGED}
    if name not in known:
        raise ValueError(f"unknown estimator {name!r}; known: {', '.join(sorted(known))}")
    module, _, class_name = known[name].partition(":")
    return getattr(importlib.import_module(module), class_name)


def estimator_settings(name: str, **options):
    """The settings of estimator ``name``: its YAML file(s) with ``options`` over them."""
    return load_settings(name, estimator_class(name).settings_type, options)


def make_estimator(name: str, **options) -> PoseEstimator:
    """A fresh estimator ``name`` with :func:`estimator_settings` ``(name, **options)``."""
    return estimator_class(name)(estimator_settings(name, **options))
