"""Pose estimators behind one interface (:class:`PoseEstimator`), chosen by name.

Settings are frozen dataclasses (:mod:`stsf_gym.estimators.settings`) whose defaults live in
``configs/estimators/<name>.yaml`` for the package's own estimators; keyword options go over
them. This package never imports the simulator (``envs``) or PyBullet: a :class:`SensorModel` is
all it knows of a robot, so it runs on logged data as well (:mod:`stsf_gym.wrappers` builds the
model from an env).

**Your own estimator.** Wherever a pose-source name is taken (the wrapper, ``gym.make(...,
estimator=...)``, ``--estimators``, sweeps, the accuracy curve, the benchmark), a
``package.module:Class`` works too: a :class:`PoseEstimator` subclass whose ``settings_type``
is a dataclass; its defaults are the dataclass's own (no YAML needed) and keyword options go
over them, checked as the package's are. A subclass of a package estimator that keeps its
parent's settings type (or extends it) keeps the parent's ``configs/estimators/`` defaults.
The module is imported as ``python -m`` would from the working directory
(``examples.complementary:ComplementaryFilter`` from the repository root).
A package that wants a short name calls :func:`register_estimator`.
"""

from __future__ import annotations

import importlib
import os
import sys

from stsf_gym.estimators.base import MapLandmark, PoseEstimator, SensorModel
from stsf_gym.estimators.settings import ESTIMATOR_DIR, build_settings, load_settings
from stsf_gym.validation import ConfigError, did_you_mean

#: Estimators by name: "module:class", imported when first made. ``conventional`` is the
#: paper's (the pose from the current two frames only), ``conventional-filter`` the same pair
#: measurement merged with the odometry prediction; ``smoother`` and ``mcl`` are the field's
#: references (:mod:`stsf_gym.estimators.references`).
ESTIMATORS: dict[str, str] = {
    "odometry": "stsf_gym.estimators.odometry_estimator:OdometryEstimator",
    "conventional": "stsf_gym.estimators.conventional:ConventionalEstimator",
    "conventional-filter": "stsf_gym.estimators.landmark_fusion:ConventionalFilterEstimator",
    "stsf": "stsf_gym.estimators.landmark_fusion:STSFEstimator",
    "ekf": "stsf_gym.estimators.ekf:EKFEstimator",
    "smoother": "stsf_gym.estimators.references.smoother:FixedLagSmoother",
    "mcl": "stsf_gym.estimators.references.mcl:MonteCarloLocalization",
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
    "estimator_class",
    "estimator_settings",
    "make_estimator",
    "register_estimator",
]


def register_estimator(name: str, cls: type[PoseEstimator] | str) -> None:
    """Make estimator class ``cls`` (or its ``"module:Class"``) known as ``name`` in this
    process; its settings are its ``settings_type``'s defaults unless
    ``configs/estimators/<name>.yaml`` exists. Worker processes started by ``spawn`` import
    afresh: there a ``module:Class`` name works without registering."""
    if not name or ":" in name:
        raise ConfigError(f"an estimator name is a word without ':', got {name!r}")
    if name in PRIVILEGED or (name in ESTIMATORS and ESTIMATORS[name] != _target(cls)):
        raise ConfigError(f"estimator {name!r} is taken by {ESTIMATORS.get(name, 'a privileged')}")
    estimator_class(_target(cls))  # fails now, naming it, if it is no estimator
    ESTIMATORS[name] = _target(cls)


def _target(cls: type | str) -> str:
    return cls if isinstance(cls, str) else f"{cls.__module__}:{cls.__qualname__}"


def estimator_class(name: str) -> type[PoseEstimator]:
    """The class of estimator (or privileged source) ``name``, or of ``package.module:Class``;
    an unknown name lists the known ones."""
    known = {**ESTIMATORS, **PRIVILEGED}
    if name not in known and ":" not in name:
        raise ConfigError(
            f"unknown estimator {name!r}{did_you_mean(name, known)}; known: "
            f"{', '.join(sorted(known))}, "
            "or a package.module:Class of your own"
        )
    module_name, _, class_name = known.get(name, name).partition(":")
    try:
        module = _import(module_name)
    except ImportError as err:
        raise ConfigError(f"estimator {name!r}: cannot import {module_name!r} ({err})") from err
    cls = getattr(module, class_name, None)
    if not (isinstance(cls, type) and issubclass(cls, PoseEstimator)):
        raise ConfigError(f"estimator {name!r}: {class_name!r} is no PoseEstimator class")
    return cls


def _import(module_name: str):
    """The module, found as ``python -m`` finds it: from the working directory too."""
    try:
        return importlib.import_module(module_name)
    except ModuleNotFoundError as err:
        if os.getcwd() in sys.path or not (err.name or "").startswith(module_name.split(".")[0]):
            raise
        sys.path.insert(0, os.getcwd())
        return importlib.import_module(module_name)


def estimator_settings(name: str, **options):
    """The settings of estimator ``name``: its YAML file(s) (a subclass of a package estimator
    without a file of its own: its parent's) with ``options`` over
    them; any other estimator (your own) has its settings dataclass's defaults."""
    cls = estimator_class(name)
    settings_type = getattr(cls, "settings_type", None)
    if settings_type is None:
        raise ConfigError(f"estimator {name!r}: {cls.__name__} has no settings_type dataclass")
    configured = _configured_name(name, cls)
    if configured is not None:
        return load_settings(configured, settings_type, options, label=name)
    return build_settings(name, settings_type, options)


def _configured_name(name: str, cls: type[PoseEstimator]) -> str | None:
    """The estimator whose ``configs/estimators/`` file holds ``cls``'s defaults: ``name``'s
    own file, else the nearest package estimator that ``cls`` subclasses with the same
    settings type or one its settings extend (a subclass keeps its parent's configured
    defaults); ``None``: the settings dataclass's own defaults."""
    if ":" not in name and (ESTIMATOR_DIR / f"{name}.yaml").is_file():
        return name
    names = {target: known for known, target in {**ESTIMATORS, **PRIVILEGED}.items()}
    for parent in cls.__mro__[1:]:
        known = names.get(_target(parent))
        if (
            known is not None
            and (ESTIMATOR_DIR / f"{known}.yaml").is_file()
            and issubclass(cls.settings_type, parent.settings_type)
        ):
            return known
    return None


def make_estimator(name: str, **options) -> PoseEstimator:
    """A fresh estimator ``name`` with :func:`estimator_settings` ``(name, **options)``."""
    return estimator_class(name)(estimator_settings(name, **options))
