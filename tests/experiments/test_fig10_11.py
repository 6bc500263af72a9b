import json

import pytest

from stsf_gym.experiments.fig10_11 import FIG11_ESTIMATORS, fig10, fig11
from stsf_gym.results import check_rows

SHORT = {"sim": {"max_episode_seconds": 3.0}}


@pytest.mark.slow
@pytest.mark.parametrize(
    ("run", "estimators"),
    [
        (fig10, ["odometry", "stsf", "ekf"]),
        (fig11, FIG11_ESTIMATORS),
    ],
)
def test_reproduce_figures_schema(tmp_path, run, estimators):
    summary = run(tmp_path, seeds=1, workers=1, env=SHORT)
    name = run.__name__
    on_disk = json.loads((tmp_path / f"{name}.json").read_text())
    assert [row["estimator"] for row in on_disk["paper_rows"]] == estimators
    assert [row["estimator"] for row in on_disk["rows"]] == estimators
    assert all("paper" in row for row in on_disk["paper_rows"])
    check_rows(on_disk["rows"])
    check_rows(on_disk["paper_rows"], "paper_rows")
    assert on_disk["seeds"] == summary["seeds"] == [0, 0]
    assert (tmp_path / f"{name}.md").read_text().startswith("# Fig.")
    assert (tmp_path / "errors.png").stat().st_size > 10_000
