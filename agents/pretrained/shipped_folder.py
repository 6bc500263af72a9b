"""A folder of shipped agents, read by its manifest.

A shipped-agents folder (the package's ``trained-models/``, or any folder ``stsf-gym agents
--ship TRAINING --ship-to DIR`` wrote) holds ``<suite>/<algo>-<pose source>/`` per agent
(``agent.json``, ``seed-S.zip`` and ``seed-S.json`` per training seed) and ``manifest.json``:
``{"files": {"<suite>/<agent>/<file>": sha256 hex}}``. A model is read only when its bytes
are those the manifest lists (:func:`checked_models`); a ship rewrites the new agent's entries
only (:func:`updated_manifest`), so a file edited by hand beside it stays refused.
"""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path

from stsf_gym.validation import ConfigError

#: In a shipped-agents folder: ``{"files": {"<suite>/<agent>/<file>": sha256 hex}}``.
MANIFEST = "manifest.json"
SUMMARY = "agent.json"  # in an agent's folder: what `stsf-gym agents` lists
#: One part of a shipped agent's name (its suite, its ``<algo>-<pose source>``): a plain file
#: name, so that no name reaches outside its shipped-agents folder (``..``, ``/``) or into a
#: folder being shipped (a leading dot).
NAME_PART = re.compile(r"[A-Za-z0-9][A-Za-z0-9_+-]*")


def valid_parts(suite: str, agent: str) -> bool:
    """Whether ``suite`` and ``agent`` are each a plain :data:`NAME_PART`."""
    return all(NAME_PART.fullmatch(part) for part in (suite, agent))


def sha256(path: Path) -> str:
    """SHA-256 (hex) of the file ``path``."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def manifest(root: Path) -> dict[str, str]:
    """``{"<suite>/<agent>/<file>": sha256}`` of the shipped agents under ``root``, as its
    manifest lists them (nothing without one)."""
    path = root / MANIFEST
    return json.loads(path.read_text())["files"] if path.is_file() else {}


def manifest_of(root: Path) -> dict:
    """The manifest the shipped agents under ``root`` have now: each file's digest."""
    files = sorted(
        p
        for p in root.glob("*/*/*")
        if p.is_file() and valid_parts(p.parent.parent.name, p.parent.name)
    )
    return {"files": {p.relative_to(root).as_posix(): sha256(p) for p in files}}


def updated_manifest(root: Path, agent: Path) -> dict:
    """``root``'s manifest with the entries of its agent folder ``agent`` digested anew (those
    of a replaced agent dropped) and every other entry as listed."""
    key = agent.relative_to(root).as_posix() + "/"
    kept = {k: v for k, v in manifest(root).items() if not k.startswith(key)}
    new = {key + p.name: sha256(p) for p in agent.iterdir() if p.is_file()}
    return {"files": dict(sorted({**kept, **new}.items()))}


def is_agent_folder(path: Path) -> bool:
    """Whether ``path`` is an agent's folder in a shipped-agents folder: ``agent.json`` in it,
    a manifest two levels up, and a plain name (:func:`valid_parts`)."""
    return (
        (path / SUMMARY).is_file()
        and (path.parent.parent / MANIFEST).is_file()
        and valid_parts(path.parent.name, path.name)
    )


def summary_of(agent: Path) -> dict:
    """``agent.json`` of the agent folder ``agent``."""
    return json.loads((agent / SUMMARY).read_text())


def checked_models(agent: Path) -> list[Path]:
    """The model file of each training seed of the agent folder ``agent``, each checked
    against its shipped-agents folder's manifest: a :class:`ConfigError` naming the first file
    whose bytes it does not list (or that is not there)."""
    root = agent.parent.parent
    listed = manifest(root)
    files = [agent / f"seed-{seed}.zip" for seed in summary_of(agent)["seeds"]]
    for file in files:
        key = file.relative_to(root).as_posix()
        digest = sha256(file) if file.is_file() else None
        if digest is None or listed.get(key) != digest:
            raise ConfigError(
                f"{file}: its bytes are not those {root / MANIFEST} lists for {key}; "
                "ship the agent again (`stsf-gym agents --ship`)"
            )
    return files
