import json
import math
import subprocess
import sys

import numpy as np
import pytest

from envs.config import ConfigError
from stsf_gym.experiments.table1 import SeedResult, Table1Run, load_table1_config, summarise
from stsf_gym.results import check_rows

SMALL = {"distances": [5.06, 5.52], "frames_per_location": 5, "seeds": 1}


@pytest.fixture(scope="module")
def small_run():
    return Table1Run(load_table1_config(**SMALL), seed=0).run()


def test_every_pair_measures_the_landmark(small_run):
    r = small_run
    assert r.location == [0] * 5 + [1] * 5
    firsts = {0, 5}  # a place's first frame has no pair yet
    for k in range(10):
        assert math.isnan(r.conventional[k]) == (k in firsts)
        assert math.isnan(r.stsf[k]) == (k in firsts)
    np.testing.assert_allclose(r.truth[:5], 5.06, atol=0.02)
    np.testing.assert_allclose(r.truth[5:], 5.52, atol=0.02)


def test_stsf_beats_conventional_and_is_close(small_run):
    r = small_run
    truth, conv, stsf = (np.array(v) for v in (r.truth, r.conventional, r.stsf))
    valid = ~np.isnan(conv)
    conventional_rms = np.sqrt(np.mean((conv[valid] - truth[valid]) ** 2))
    assert abs(stsf[-1] - truth[-1]) < conventional_rms
    assert abs(stsf[-1] - truth[-1]) < 0.25
    assert stsf[1] == pytest.approx(conv[1])  # a one-measurement track is the conventional result


def test_summary_rows_have_paper_and_bound():
    cfg = load_table1_config(**SMALL)
    result = SeedResult(
        [0, 0, 1, 1],
        [5.0, 5.0, 5.5, 5.5],
        [math.nan, 5.2, math.nan, 5.4],
        [math.nan, 5.1, math.nan, 5.45],
        [math.nan, 5.1, math.nan, 5.4],
    )
    rows = summarise(cfg, [result])
    assert [row["world (m)"] for row in rows] == [5.06, 5.52]
    assert rows[0]["conventional error (m)"] == pytest.approx(0.2)
    assert rows[1]["STSF error (m)"] == pytest.approx(0.05)
    assert rows[1]["STSF-GLS error (m)"] == pytest.approx(0.1)
    assert rows[0]["paper STSF error (m)"] == 0.14
    f = 240 / math.tan(math.radians(15))
    assert rows[0]["bound (m)"] == pytest.approx(math.sqrt(2) * 5.06**2 * 0.5 / (f * 0.122))


def test_bad_experiment_key_is_named():
    with pytest.raises(ConfigError, match=r"table1\.frames"):
        load_table1_config(frames=3)


def test_cli_reproduce_table1_json(tmp_path):
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "stsf_gym.cli",
            "reproduce",
            "table1",
            "--json",
            "--out",
            str(tmp_path),
            "--seeds",
            "1",
            "--workers",
            "1",
            "--set",
            "frames_per_location=3",
            "--set",
            "distances=[5.06]",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    rows = json.loads(result.stdout)["rows"]
    assert len(rows) == 1 and rows[0]["pairs"] == 2
    check_rows(rows)
    assert (tmp_path / "table1" / "table1.png").stat().st_size > 10_000
    assert "| row |" in (tmp_path / "table1" / "table1.md").read_text()
