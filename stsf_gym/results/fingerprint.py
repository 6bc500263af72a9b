"""What a cached unit of work is reused for: its code's behaviour versions and the digest of its
resolved configuration.

Every cached unit of work (an episode, a sweep cell, a Table I seed, a training checkpoint) is
stamped with a :func:`fingerprint`, so a rerun reuses it only when both are unchanged; a
results file of many units records each distinct configuration once (:func:`by_digest`).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from stsf_gym.results.behaviour import versions_digest


def canonical(value: Any) -> Any:
    """``value`` as JSON takes it: an array as a list, a path as a string."""
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"cannot identify a {type(value).__name__} in a configuration")


def config_digest(config: Mapping[str, Any]) -> str:
    """SHA-256 (hex, 16 digits) of ``config`` as canonical JSON (sorted keys)."""
    text = json.dumps(config, sort_keys=True, default=canonical, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def by_digest(configs: Mapping[str, Mapping[str, Any]]) -> dict[str, dict]:
    """Resolved configurations of many units (by unit name) as a provenance records them:
    each distinct one once under its :func:`config_digest`, and each unit's digest."""
    digests = {name: config_digest(config) for name, config in configs.items()}
    return {
        "configs": {digests[name]: dict(config) for name, config in configs.items()},
        "units": digests,
    }


def fingerprint(config: Mapping[str, Any] | None = None) -> dict[str, str]:
    """What a cached unit of work is reused for: the behaviour versions of the code
    (:func:`~stsf_gym.results.behaviour.versions_digest`) and its configuration's digest."""
    return {"code": versions_digest(), "config": config_digest(config or {})}
