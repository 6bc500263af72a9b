"""benchmarks/goal_bearing.py: misses split by the goal's bearing off the route's first leg."""

from __future__ import annotations

import json
import subprocess
import sys

from helpers import ROOT


def test_misses_split_by_the_goal_bearing(tmp_path):
    """Corridor test world 34's goal lies behind its start (163 degrees off the first leg),
    world 0's ahead: a miss on each lands on its side of the split."""
    row = {"seeds": [0, 34], "success_rate": {"values": [0.0, 0.0]}}
    results = {
        "suite": "corridor",
        "rows": [
            {**row, "agent": "a", "estimator": "truth"},
            {
                "agent": "b",
                "estimator": "truth",
                "seeds": [0, 34],
                "success_rate": {"values": [1.0, 0.0]},
            },
        ],
    }
    path = tmp_path / "results.json"
    path.write_text(json.dumps(results))
    command = [sys.executable, str(ROOT / "benchmarks" / "goal_bearing.py"), str(path), "--json"]
    rows = json.loads(subprocess.run(command, capture_output=True, text=True, check=True).stdout)
    assert [(r["beyond"], r["within"]) for r in rows] == [
        ({"worlds": 1, "misses": 1}, {"worlds": 1, "misses": 1}),
        ({"worlds": 1, "misses": 1}, {"worlds": 1, "misses": 0}),
    ]
