"""The job store on a full disk: SQLite's ``SQLITE_FULL`` is the ``ENOSPC`` every other write
raises (the command line's one line), the rows written before stay, and the store is not set
aside as unreadable."""

from __future__ import annotations

import errno
import sqlite3

import pytest

from stsf_gym.experiments.jobs import store


@pytest.fixture
def full_disk(monkeypatch):
    """Every connection opened after it may not grow its file: SQLite's own full disk
    (``PRAGMA max_page_count`` at the file's size), not a mock of the error."""
    connect = sqlite3.connect

    def connect_full(*args, **kwargs):
        db = connect(*args, **kwargs)
        db.execute("PRAGMA max_page_count = 1")  # clamps to the pages the file has
        return db

    return lambda: monkeypatch.setattr(sqlite3, "connect", connect_full)


def test_a_full_disk_under_the_store_is_enospc_and_keeps_what_was_written(tmp_path, full_disk):
    path = store.open_store(tmp_path / "cells.sqlite")
    store.write_row(path, "first", {"seed": 0}, "config", {"a.py": "1"}, {"outcome": "goal"})
    full_disk()
    with pytest.raises(OSError) as raised:
        store.write_row(path, "second", {"seed": 1}, "config", {"a.py": "1"}, "x" * 200_000)
    assert raised.value.errno == errno.ENOSPC and raised.value.filename == str(path)
    assert store.open_store(path) == path  # a full disk is no unreadable store
    assert not path.with_name("cells.sqlite.unreadable").exists()
    assert list(store.read_rows(path)) == ["first"]
    assert store.read_rows(path)["first"].result == {"outcome": "goal"}


def test_a_full_disk_under_a_command_is_one_line(run_cli, tmp_path, full_disk):
    out = tmp_path / "out"
    store.open_store(out / "episodes.sqlite")  # the store exists, its file can grow no more
    full_disk()
    code, err = run_cli(
        "evaluate", "--estimators", "truth", "--seeds", "1", "--workers", "1",
        "--set", "camera.enabled=false", "--set", "sim.max_episode_seconds=0.5",
        "--out", str(out),
    )  # fmt: skip
    assert code == 1 and len(err.strip().splitlines()) == 1, err
    assert "the disk is full writing" in err and "free space and rerun" in err
