"""A run's finished jobs in one SQLite file: the store the job cache reads and writes.

One row per job, written in its own transaction as the job finishes, so a kill (SIGKILL
included) leaves a store that opens with every job that had finished; a store that does not
open as SQLite (another file under its name) is set aside as ``<name>.unreadable`` and the run
starts a new one. A full disk (SQLite's ``SQLITE_FULL``) is the ``OSError`` ``ENOSPC`` naming the
store, as any other file's write says it: the transaction is rolled back, every row written
before stays, and the store is never set aside for it. The schema (``docs/results_schema.md``):

- ``results(key, job, config, code, result, written_ns)``: the job's key, the job and its
  result as JSON, the digest of its resolved configuration, the digest of the code it ran
  with (a row of ``code``) and when the row was written;
- ``code(digest, files)``: each distinct record of code (``{relative path: code digest}``,
  :mod:`stsf_gym.results.freshness`) once;
- ``meta(name, value)``: ``schema`` (:data:`SCHEMA`).
"""

from __future__ import annotations

import errno
import json
import os
import sqlite3
import sys
import time
from collections.abc import Iterable, Iterator, Mapping
from contextlib import closing, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stsf_gym.io import to_builtin
from stsf_gym.results.fingerprint import config_digest

SCHEMA = 1
TABLES = (
    "CREATE TABLE IF NOT EXISTS results (key TEXT PRIMARY KEY, job TEXT NOT NULL,"
    " config TEXT NOT NULL, code TEXT NOT NULL, result TEXT NOT NULL,"
    " written_ns INTEGER NOT NULL)",
    "CREATE TABLE IF NOT EXISTS code (digest TEXT PRIMARY KEY, files TEXT NOT NULL)",
    "CREATE TABLE IF NOT EXISTS meta (name TEXT PRIMARY KEY, value TEXT NOT NULL)",
)


@dataclass(frozen=True)
class Row:
    """A finished job as stored: the job, its config digest, its code record, its result."""

    job: dict
    config: str
    code: dict[str, str]
    result: Any
    written_ns: int


@contextmanager
def _open(path: Path) -> Iterator[sqlite3.Connection]:
    """A connection to the store at ``path``; SQLite's full disk raised as ``ENOSPC``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        with closing(sqlite3.connect(path)) as db:
            db.execute("PRAGMA synchronous = FULL")
            yield db
    except sqlite3.OperationalError as err:
        if getattr(err, "sqlite_errorcode", None) != sqlite3.SQLITE_FULL:
            raise
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path)) from err


def _set_aside(path: Path, err: sqlite3.DatabaseError) -> None:
    aside = path.with_name(path.name + ".unreadable")
    path.replace(aside)
    print(f"{path} is not a readable store ({err}); set aside as {aside}", file=sys.stderr)


def open_store(path: str | Path) -> Path:
    """Create the store at ``path`` (or check the one there); return its path."""
    path = Path(path)
    for attempt in range(2):
        try:
            with _open(path) as db, db:
                for table in TABLES:
                    db.execute(table)
                db.execute("INSERT OR IGNORE INTO meta VALUES ('schema', ?)", (str(SCHEMA),))
            return path
        except sqlite3.DatabaseError as err:
            if attempt or not path.is_file():
                raise
            _set_aside(path, err)
    return path


def read_rows(path: str | Path) -> dict[str, Row]:
    """Every row of the store at ``path`` by key (nothing when there is none)."""
    path = Path(path)
    if not path.is_file():
        return {}
    with _open(path) as db:
        codes = {d: json.loads(files) for d, files in db.execute("SELECT digest, files FROM code")}
        rows = db.execute("SELECT key, job, config, code, result, written_ns FROM results")
        return {
            key: Row(json.loads(job), config, codes[code], json.loads(result), written)
            for key, job, config, code, result, written in rows
        }


def write_row(
    path: Path, key: str, job: dict, config: str, code: Mapping[str, str], result: Any
) -> None:
    """Store the finished ``job`` under ``key`` (replacing a row of that key), in one
    transaction."""
    files = json.dumps(dict(sorted(code.items())))
    digest = config_digest(dict(code))
    with _open(path) as db, db:
        db.execute("INSERT OR IGNORE INTO code VALUES (?, ?)", (digest, files))
        db.execute(
            "INSERT OR REPLACE INTO results VALUES (?, ?, ?, ?, ?, ?)",
            (
                key,
                json.dumps(job, sort_keys=True),
                config,
                digest,
                json.dumps(result, default=to_builtin),
                time.time_ns(),
            ),
        )


def delete_rows(path: Path, keys: Iterable[str]) -> None:
    """Remove the rows of ``keys`` (and code records no row uses any more)."""
    with _open(path) as db, db:
        db.executemany("DELETE FROM results WHERE key = ?", [(key,) for key in keys])
        db.execute("DELETE FROM code WHERE digest NOT IN (SELECT code FROM results)")
