"""examples/own_robot_log.py: a log written by a plain script (no env) replays through the
documented format, and the landmark estimators use its detections."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from helpers import ROOT


@pytest.mark.slow
def test_a_plain_script_log_replays(tmp_path):
    script = ROOT / "examples" / "own_robot_log.py"
    subprocess.run([sys.executable, str(script), "--out", str(tmp_path)], check=True, cwd=ROOT)
    assert (tmp_path / "own_robot.mcap").is_file()
    rows = {
        row["estimator"]: row
        for row in json.loads((tmp_path / "replay" / "results.json").read_text())["rows"]
    }
    assert rows["odometry"]["match_rate"]["mean"] is None  # odometry looks at no frame
    for name in ("stsf", "ekf"):
        assert rows[name]["match_rate"]["mean"] > 0.5
        assert rows[name]["ate_rmse_m"]["mean"] < rows["odometry"]["ate_rmse_m"]["mean"] / 5
