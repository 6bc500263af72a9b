"""What a number depends on, in a form a refactor does not touch: behaviour versions.

The code is cut into subsystems, each with a version (like Gymnasium's ``-vN``). A change that
may move any number a subsystem makes (a trajectory, an estimate, an action, a reward, a score)
bumps its version in :data:`VERSIONS`, in the same commit; a rewrite that keeps every number
(a compiled loop, a renamed function, a docstring) leaves it.
``tests/behaviour/test_step_equality.py`` is the proof for the simulated world, the estimators
and the follower: its golden episodes are replayed to the last bit, and they record the versions
they were made with, so new goldens can only be written under new versions.

A results file records the versions of the subsystems its run loaded (:func:`behaviour`); a
figure quoting it goes stale when one of them moves (``benchmarks/measured_blocks.py``), and a
cached unit of work is reused only under the same versions (:func:`versions_digest`). Timings
are the exception: any rewrite may change them, so they depend on the code itself, read by
:func:`code_digest` without its docstrings and comments.
"""

from __future__ import annotations

import ast
import hashlib
import json
from collections.abc import Iterable
from pathlib import Path

import yaml

#: Each subsystem's behaviour version: bump it when a number it makes may change.
VERSIONS: dict[str, int] = {
    "world": 1,  # envs/: physics, sensors, worlds, task and reward
    "estimation": 1,  # fusion, vision, estimators, the estimate wrapper and their configs
    "follower": 1,  # the scripted agents
    "learner": 1,  # policies, observations, demonstrations, training, shipped agents' use
    "scoring": 1,  # metrics, statistics, experiment runners, results
}

#: Repository-relative path prefixes of each subsystem; the longest matching prefix wins, and a
#: path no prefix matches (the CLI, terminal tables, videos) makes no number.
PREFIXES: dict[str, str] = {
    "envs/": "world",
    "configs/": "world",
    "stsf_gym/geometry.py": "world",
    "stsf_gym/camera_model.py": "world",
    "stsf_gym/config.py": "world",
    "stsf_gym/config_files.py": "world",
    "stsf_gym/recording/": "world",
    "stsf_gym/fusion/": "estimation",
    "stsf_gym/vision/": "estimation",
    "stsf_gym/estimators/": "estimation",
    "stsf_gym/wrappers/": "estimation",
    "stsf_gym/episode_env.py": "estimation",
    "configs/estimators/": "estimation",
    "agents/": "learner",
    "configs/agents/": "learner",
    "agents/follower.py": "follower",
    "agents/sonar_avoidance.py": "follower",
    "configs/agents/follower.yaml": "follower",
    "stsf_gym/experiments/": "scoring",
    "stsf_gym/results/": "scoring",
    "stsf_gym/metrics.py": "scoring",
    "stsf_gym/tum.py": "scoring",
    "configs/experiments/": "scoring",
    "configs/sweeps/": "scoring",
}


def subsystem(path: str) -> str | None:
    """The subsystem of a repository-relative ``path`` (``envs/robot.py``), or None."""
    matches = [prefix for prefix in PREFIXES if path.startswith(prefix)]
    return PREFIXES[max(matches, key=len)] if matches else None


def behaviour(paths: Iterable[str]) -> dict[str, int]:
    """``{subsystem: version}`` of the subsystems the code ``paths`` belong to."""
    names = {name for path in paths if (name := subsystem(path)) is not None}
    return {name: VERSIONS[name] for name in sorted(names)}


def versions_digest(versions: dict[str, int] | None = None) -> str:
    """SHA-256 (hex, 16 digits) of ``versions`` (default: every subsystem's now)."""
    text = json.dumps(VERSIONS if versions is None else versions, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _without_docstrings(tree: ast.AST) -> ast.AST:
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr):
            value = body[0].value
            if isinstance(value, ast.Constant) and isinstance(value.value, str):
                setattr(node, "body", body[1:] or [ast.Pass()])  # noqa: B010 - any node's body
    return tree


def code_text(path: Path) -> bytes:
    """What ``path`` computes, without what it says: a module's syntax tree with its
    docstrings and comments left out, a YAML file's data, any other file's bytes."""
    if path.suffix == ".py":
        return ast.unparse(_without_docstrings(ast.parse(path.read_bytes()))).encode()
    if path.suffix == ".yaml":
        return json.dumps(yaml.safe_load(path.read_text()), sort_keys=True).encode()
    return path.read_bytes()


def code_digest(path: Path) -> str:
    """SHA-256 (hex, 16 digits) of :func:`code_text`: an edit of words only leaves it."""
    return hashlib.sha256(code_text(path)).hexdigest()[:16]
