"""Which rows of a store the code of this checkout would recompute, and the modules why.

``python benchmarks/studies/stale_rows.py STORE`` prints the rows whose recorded code no longer
computes what it did (:class:`~stsf_gym.results.freshness.CurrentCode`), by changed module: the
check a rerun makes before it runs anything (a row's configuration is checked too, by the run).
Used to show that a scoring change recomputes the cells it touches and no others
(``docs/results_schema.md``).
"""

from __future__ import annotations

import json
import sys
from collections import Counter

from stsf_gym.experiments.jobs.store import read_rows
from stsf_gym.results.freshness import CurrentCode


def stale_rows(store: str) -> dict:
    """``{"rows", "current", "stale", "by_module": {module: rows}}`` of ``store``."""
    rows, code = read_rows(store), CurrentCode()
    changed = {key: code.changed(row.code) for key, row in rows.items()}
    by_module = Counter(module for modules in changed.values() for module in modules)
    stale = sum(bool(modules) for modules in changed.values())
    return {
        "rows": len(rows),
        "current": len(rows) - stale,
        "stale": stale,
        "by_module": dict(by_module),
    }


if __name__ == "__main__":
    print(json.dumps(stale_rows(sys.argv[1]), indent=1))
