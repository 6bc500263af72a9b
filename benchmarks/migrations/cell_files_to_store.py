"""Move a results folder's cells from one JSON file each (``cells/*.json``) into its store.

``python benchmarks/migrations/cell_files_to_store.py FOLDER`` (e.g.
``benchmarks/results/reward-benchmark/sparse``) writes ``FOLDER/cells.sqlite`` and removes
``FOLDER/cells/``. A file's cell is carried over only when it is current by the rule it was
made under: the behaviour versions it was stamped with are today's and its configuration's
digest is what today's code resolves for it. The files do not say which modules made them, so
each row is stamped with the code a worker of today's checkout loads for such cells, measured:
one short episode of each agent kind (scripted or learnt) on each pose source, in a fresh
process. This trusts the declared versions one last time; from then on freshness is derived
(:mod:`stsf_gym.results.freshness`).
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

from stsf_gym.experiments.jobs.cells import cell_config
from stsf_gym.experiments.jobs.store import open_store, write_row
from stsf_gym.results.behaviour import versions_digest
from stsf_gym.results.fingerprint import config_digest
from stsf_gym.results.freshness import CurrentCode

PROBE = """
import json, sys
from stsf_gym.experiments.jobs.cells import evaluate_cell
from stsf_gym.results.code_identity import loaded_modules
for cell in json.load(sys.stdin):
    evaluate_cell(cell)
print(json.dumps(loaded_modules()))
"""


def worker_modules(cells: list[dict]) -> list[str]:
    """The package modules a fresh worker has loaded after a short episode of each agent kind
    on each pose source of ``cells``."""
    kinds = {}
    for cell in cells:
        learnt = cell["agent"].endswith(".zip")
        kinds.setdefault((learnt, cell["estimator"]), cell)
    short = [
        {**cell, "env": {**cell["env"], "sim": {"max_episode_seconds": 2.0}}}
        for cell in kinds.values()
    ]
    done = subprocess.run(
        [sys.executable, "-c", PROBE],
        input=json.dumps(short),
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(done.stdout.splitlines()[-1])


def migrate(folder: Path) -> dict[str, int]:
    """Carry ``folder/cells/*.json`` into ``folder/cells.sqlite``; the counts of each fate."""
    files = sorted((folder / "cells").glob("*.json"))
    records = {file.stem: json.loads(file.read_text()) for file in files}
    for record in records.values():
        record["job"].pop("version", None)  # the per-kind version, no longer part of a job
    configs: dict[str, str] = {}
    current, stale = {}, []
    for key, record in records.items():
        config = config_digest(cell_config(record["job"]))
        made_by = record["made_by"]
        if made_by == {"code": versions_digest(), "config": config}:
            current[key], configs[key] = record, config
        else:
            stale.append(key)
    code = CurrentCode().record(worker_modules([r["job"] for r in current.values()]))
    store = open_store(folder / "cells.sqlite")
    for key, record in current.items():
        write_row(store, key, record["job"], configs[key], code, record["result"])
    shutil.rmtree(folder / "cells")
    return {"files": len(files), "carried": len(current), "stale, left out": len(stale)}


if __name__ == "__main__":
    print(migrate(Path(sys.argv[1])))
