"""Declare a rewrite equivalent for a store's rows: the override of derived freshness.

``python benchmarks/migrations/declare_equivalent.py STORE [--sample N]`` is for a rewrite that
keeps every number (an import path moved, a type annotation fixed) but changes modules a
store's rows recorded, which would otherwise be recomputed. It first **tests** the claim: ``N``
of the stale rows (spread over the store, default 4) are run again with today's code and their
results must equal the stored ones, timings aside; only then is every row whose configuration
is still today's stamped with today's code of the modules it recorded. It prints the modules
that changed, the rows rerun and the rows stamped.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from stsf_gym.experiments.jobs.cells import cell_config, run_cell
from stsf_gym.experiments.jobs.store import read_rows, write_row
from stsf_gym.results.fingerprint import config_digest
from stsf_gym.results.freshness import CurrentCode

#: Result keys that are measurements of time, different on every run.
TIMING = {"ms_per_step", "stage_ms_per_step", "wall_time_s", "train_wall_time_s"}


def untimed(value):
    """``value`` without its :data:`TIMING` entries, as JSON reads it back."""
    if isinstance(value, dict):
        return {k: untimed(v) for k, v in value.items() if k not in TIMING}
    if isinstance(value, list):
        return [untimed(v) for v in value]
    return value


def declare(store: Path, sample: int) -> dict:
    """Test the rewrite on ``sample`` stale rows, then stamp the rows of ``store`` (see the
    module); ValueError when a rerun row differs."""
    rows, code = read_rows(store), CurrentCode()
    stale = sorted(key for key, row in rows.items() if code.changed(row.code))
    changed = sorted({path for key in stale for path in code.changed(rows[key].code)})
    rerun = stale[:: max(1, len(stale) // sample)][:sample] if stale else []
    for key in rerun:
        again = json.loads(json.dumps(run_cell(rows[key].job)))
        if untimed(again) != untimed(rows[key].result):
            raise ValueError(f"{key}: today's code computes another result; not equivalent")
    stamped = 0
    for key in stale:
        row = rows[key]
        if config_digest(cell_config(row.job)) != row.config:
            continue  # another configuration now: to be recomputed, not declared
        write_row(store, key, row.job, row.config, code.record(row.code), row.result)
        stamped += 1
    return {"changed_modules": changed, "rerun_equal": rerun, "stamped": stamped}


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("store", type=Path)
    parser.add_argument("--sample", type=int, default=4, help="stale rows run again first (4)")
    args = parser.parse_args()
    print(json.dumps(declare(args.store, args.sample), indent=1))
