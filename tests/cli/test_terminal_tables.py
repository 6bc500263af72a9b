"""Tables printed to a pipe (not a terminal: 80 columns) keep their headline columns, and a
results file leads with a headline table."""

import io
import json
import subprocess
import sys

from helpers import ROOT
from rich.console import Console

from stsf_gym.experiments.result_tables import HEADLINE, results_tables
from stsf_gym.results import METRICS
from stsf_gym.terminal_table import print_markdown

FIG11 = ROOT / "benchmarks/results/paper/fig11/results.json"
RUNS = {
    "ekf on ekf - mcl on mcl": ["-0.34 (-0.46 to -0.20)", "-0.50 (-0.60 to -0.37)"],
    "stsf on stsf - mcl on mcl": ["+0.01 (-0.08 to +0.10)", "+0.00 (-0.09 to +0.09)"],
}
PAIRED = (
    "| first - second | per run (95 % CI) | runs whose CI excludes 0 |\n|---|---|---|\n"
    + "".join(f"| {pair} | {'; '.join(runs * 2)} | 3 of 3 |\n" for pair, runs in RUNS.items())
)


def _printed(markdown: str) -> str:
    out = io.StringIO()
    print_markdown(markdown, Console(file=out), "results.md")  # a file: not a terminal
    return out.getvalue()


def test_a_list_of_figures_breaks_at_its_figures_not_the_table():
    text = _printed(PAIRED)
    assert "more column" not in text and "3 of 3" in text
    assert "-0.34 (-0.46 to -0.20);" in text and "+0.00 (-0.09 to +0.09)" in text  # whole
    assert max(len(line) for line in text.splitlines()) <= 80


def test_a_table_to_a_pipe_keeps_its_headline_columns():
    """The CLI's own stdout to a pipe: every headline column of an evaluate report shown."""
    rows = json.loads(FIG11.read_text())["rows"]
    rows[0]["estimator"] = "examples.complementary:ComplementaryFilter"
    script = (
        "import sys; from rich.console import Console; "
        "from stsf_gym.terminal_table import print_markdown; "
        "print_markdown(sys.stdin.read(), Console(), 'results.md')"
    )
    markdown = results_tables(rows)
    piped = subprocess.run(
        [sys.executable, "-c", script], input=markdown, capture_output=True, text=True, check=True
    ).stdout
    headline = piped.split("## ")[0]
    assert "more column" not in headline
    for key in HEADLINE[1:]:
        for word in METRICS.get(key, key).split():
            assert word in headline, (word, headline)
    assert "0.242 ± 0.064" in headline  # odometry's ATE, whole


def test_results_tables_lead_with_the_headline_and_keep_every_column():
    rows = [{**row, "extra": 1.0} for row in json.loads(FIG11.read_text())["rows"]]
    text = results_tables(rows)
    assert text.splitlines()[0].startswith("| estimator | success rate | collision rate |")
    assert "## Localization" in text and "## NEES" in text and "## Other" in text
    shown = " | ".join(line for line in text.splitlines() if line.startswith("| estimator"))
    for key in set(rows[0]) - {"seeds", "agent"}:
        assert f" {METRICS.get(key, key)} |" in shown, key
