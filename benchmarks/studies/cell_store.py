"""Which store holds a run's cells: SQLite, JSONL or Parquet, measured on a real benchmark.

Reads the cells of a committed benchmark (one JSON file per cell, as before the store, or the
store itself) and writes them into each candidate the way a run does, one cell at a time:

- size on disk, and ``.git`` growth when the store is committed into a scratch repository
  (``git count-objects`` after ``git gc``), beside the one-file-per-cell layout;
- write safety: a child process writes cells and reports each one finished; it is killed with
  SIGKILL at random moments, and the store must then read, holding every reported cell;
- read speed: every cell read back and parsed (best of 3).

``python benchmarks/studies/cell_store.py [FOLDER]`` prints the table that
``docs/results_schema.md`` quotes.
"""

from __future__ import annotations

import json
import os
import random
import signal
import sqlite3
import subprocess
import sys
import tempfile
import time
from pathlib import Path

RUN = Path("benchmarks/results/reward-benchmark/sparse")
KILLS = 20  # SIGKILLs per candidate
STEP = 400  # cells per commit of a run committed as it goes


def read_cells(folder: Path) -> list[tuple[str, str]]:
    """``(key, record as JSON text)`` of every cell of ``folder`` (its store or its files)."""
    store = folder / "cells.sqlite"
    if store.is_file():
        with sqlite3.connect(store) as db:
            rows = db.execute("SELECT key, job, made_by, result FROM cells ORDER BY key")
            return [
                (
                    key,
                    json.dumps(
                        {"job": json.loads(j), "made_by": json.loads(m), "result": json.loads(r)}
                    ),
                )
                for key, j, m, r in rows
            ]
    files = sorted((folder / "cells").glob("*.json"))
    return [(f.stem, json.dumps(json.loads(f.read_text()))) for f in files]


def write_sqlite(path: Path, cells: list[tuple[str, str]], report=None) -> None:
    db = sqlite3.connect(path)
    db.execute("CREATE TABLE IF NOT EXISTS cells (key TEXT PRIMARY KEY, record TEXT)")
    for key, record in cells:
        with db:
            db.execute("INSERT OR REPLACE INTO cells VALUES (?, ?)", (key, record))
        report and report(key)
    db.close()


def read_sqlite(path: Path) -> dict:
    with sqlite3.connect(path) as db:
        return {k: json.loads(r) for k, r in db.execute("SELECT key, record FROM cells")}


def write_jsonl(path: Path, cells: list[tuple[str, str]], report=None) -> None:
    with open(path, "a") as f:
        for key, record in cells:
            f.write(json.dumps({"key": key, **json.loads(record)}) + "\n")
            f.flush()
            os.fsync(f.fileno())
            report and report(key)


def read_jsonl(path: Path) -> dict:
    found = {}
    for line in path.read_text().splitlines():
        try:
            record = json.loads(line)
        except ValueError:  # the line a kill cut short
            continue
        found[record.pop("key")] = record
    return found


def write_parquet(path: Path, cells: list[tuple[str, str]], report=None) -> None:
    """Parquet files are written whole: each cell rewrites the file (temporary + rename)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    done: list[tuple[str, str]] = []
    if path.is_file():
        table = pq.read_table(path)
        done = list(zip(table["key"].to_pylist(), table["record"].to_pylist(), strict=True))
    for key, record in cells:
        done.append((key, record))
        table = pa.table({"key": [k for k, _ in done], "record": [r for _, r in done]})
        tmp = path.with_suffix(".tmp")
        pq.write_table(table, tmp, compression="zstd")
        os.replace(tmp, path)
        report and report(key)


def read_parquet(path: Path) -> dict:
    import pyarrow.parquet as pq

    table = pq.read_table(path)
    return {
        k: json.loads(r)
        for k, r in zip(table["key"].to_pylist(), table["record"].to_pylist(), strict=True)
    }


CANDIDATES = {
    "sqlite": (write_sqlite, read_sqlite, "cells.sqlite"),
    "jsonl": (write_jsonl, read_jsonl, "cells.jsonl"),
    "parquet": (write_parquet, read_parquet, "cells.parquet"),
}


def git_growth(*commits: dict[str, bytes]) -> int:
    """Bytes ``.git`` grows by (packed, after ``git gc``) when each of ``commits`` (the files
    it writes) is committed in turn."""
    with tempfile.TemporaryDirectory() as tmp:
        git = ["git", "-C", tmp, "-c", "user.name=s", "-c", "user.email=s@s"]
        subprocess.run([*git, "init", "-q"], check=True)
        subprocess.run([*git, "commit", "-q", "--allow-empty", "-m", "0"], check=True)
        subprocess.run([*git, "gc", "-q"], check=True)
        before = _packed(tmp)
        for files in commits:
            for name, data in files.items():
                (Path(tmp) / name).parent.mkdir(parents=True, exist_ok=True)
                (Path(tmp) / name).write_bytes(data)
            subprocess.run([*git, "add", "-A"], check=True)
            subprocess.run([*git, "commit", "-q", "-m", "1"], check=True)
        subprocess.run([*git, "gc", "-q"], check=True)
        return _packed(tmp) - before


def store_bytes(name: str, cells: list[tuple[str, str]]) -> bytes:
    """The store ``name`` holding ``cells``, as bytes."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / CANDIDATES[name][2]
        (_parquet_whole if name == "parquet" else CANDIDATES[name][0])(path, cells)
        return path.read_bytes()


def _packed(repo: str) -> int:
    out = subprocess.run(
        ["git", "-C", repo, "count-objects", "-v"], capture_output=True, text=True, check=True
    ).stdout
    sizes = dict(line.split(": ") for line in out.splitlines())
    return 1024 * (int(sizes["size-pack"]) + int(sizes["size"]))


def kill_trials(name: str, cells: list[tuple[str, str]], kills: int = KILLS) -> tuple[int, ...]:
    """SIGKILL a writer ``kills`` times; return (trials whose store read with every reported
    cell, cells lost in all, cells reported in all)."""
    ok, lost, written = 0, 0, 0
    rng = random.Random(0)
    with tempfile.TemporaryDirectory() as tmp:
        for trial in range(kills):
            store = Path(tmp) / f"{trial}-{CANDIDATES[name][2]}"
            child = subprocess.Popen(
                [sys.executable, __file__, "--write", name, str(store)],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                text=True,
            )
            child.stdin.write(json.dumps(cells[:400]))
            child.stdin.close()
            reported = []
            deadline = time.monotonic() + rng.uniform(0.2, 1.5)
            os.set_blocking(child.stdout.fileno(), False)
            while time.monotonic() < deadline and child.poll() is None:
                reported += [line for line in (child.stdout.readline(),) if line]
            child.send_signal(signal.SIGKILL)
            child.wait()
            reported += child.stdout.read().splitlines() if child.stdout else []
            reported = [line.strip() for line in reported if line.strip()]
            try:
                found = CANDIDATES[name][1](store) if store.exists() else {}
            except Exception:  # an unreadable store loses everything
                found = {}
            missing = [key for key in reported if key not in found]
            ok += not missing
            lost += len(missing)
            written += len(reported)
    return ok, lost, written


def measure(folder: Path) -> list[dict]:
    cells = read_cells(folder)
    files = {
        f"cells/{key}.json": (json.dumps(json.loads(r), indent=2) + "\n").encode()
        for key, r in cells
    }
    steps = range(STEP, len(cells) + STEP, STEP)
    rows = [
        {
            "store": "one JSON file per cell",
            "files": len(files),
            "bytes": sum(map(len, files.values())),
            "git_growth": git_growth(files),
            f"git_growth_{len(steps)}_commits": git_growth(
                *[dict(list(files.items())[n - STEP : n]) for n in steps]
            ),
        }
    ]
    for name, (write, read, file) in CANDIDATES.items():
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / file
            start = time.perf_counter()
            write(path, cells[:200])  # a run's writes, cell by cell (Parquet: 200 only)
            per_cell_ms = 1000 * (time.perf_counter() - start) / 200
            path.unlink()
            (_parquet_whole if name == "parquet" else write)(path, cells)
            reads = []
            for _ in range(3):
                start = time.perf_counter()
                assert len(read(path)) == len(cells)
                reads.append(time.perf_counter() - start)
            start = time.perf_counter()
            write(path, [("one-more", cells[0][1])])
            last_ms = 1000 * (time.perf_counter() - start)
            ok, lost, written = kill_trials(name, cells)
            grown = [{file: store_bytes(name, cells[:n])} for n in steps]
            rows.append(
                {
                    "store": name,
                    "files": 1,
                    "bytes": path.stat().st_size,
                    "git_growth": git_growth({file: path.read_bytes()}),
                    f"git_growth_{len(steps)}_commits": git_growth(*grown),
                    "write_ms_last_cell": round(last_ms, 2),
                    "write_ms_per_cell": round(per_cell_ms, 2),
                    "read_all_s": round(min(reads), 3),
                    "kills_readable_and_complete": f"{ok}/{KILLS}",
                    "cells_reported_before_kills": written,
                    "cells_lost": lost,
                }
            )
    return rows


def _parquet_whole(path: Path, cells: list[tuple[str, str]]) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    pq.write_table(
        pa.table({"key": [k for k, _ in cells], "record": [r for _, r in cells]}),
        path,
        compression="zstd",
    )


def _child(name: str, store: str) -> None:
    cells = json.loads(sys.stdin.read())

    def report(key: str) -> None:
        print(key, flush=True)

    CANDIDATES[name][0](Path(store), [tuple(c) for c in cells], report)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--write"]:
        _child(sys.argv[2], sys.argv[3])
    else:
        rows = measure(Path(sys.argv[1]) if len(sys.argv) > 1 else RUN)
        columns = list(rows[-1])
        print("| " + " | ".join(columns) + " |\n|" + "---|" * len(columns))
        for row in rows:
            print("| " + " | ".join(str(row.get(c, "")) for c in columns) + " |")
