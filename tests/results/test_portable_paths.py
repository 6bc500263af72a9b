"""Commands as a user would type them: a run records its absolute paths by name (``OUT``,
``BASELINE``, ``CONFIG``, ``MODEL``), and no page, committed result or shipped agent carries a
path of the machine it was made on."""

from __future__ import annotations

import json
import re
import zipfile

import pytest
from helpers import ROOT

from stsf_gym.results import command
from stsf_gym.results.run_context import RunContext, run_context

#: An absolute path of a machine: its user, work or scratch folders.
MACHINE_PATH = re.compile(r"(?<![\w.~-])/(?:work|tmp|home|root|Users|mnt|media|srv|opt)/\w")
TEXT = (".md", ".json", ".yaml", ".txt")


def _shipped_texts() -> list[tuple[str, str]]:
    """(where, text) of every text file a user reads or the wheel ships, and of every JSON
    entry inside a shipped model."""
    folders = [ROOT / "docs", ROOT / "benchmarks" / "results", ROOT / "agents" / "pretrained"]
    files = [ROOT / "README.md", *(p for f in folders for p in sorted(f.rglob("*")))]
    texts = [(str(p.relative_to(ROOT)), p.read_text()) for p in files if p.suffix in TEXT]
    for model in sorted((ROOT / "agents" / "pretrained").rglob("*.zip")):
        with zipfile.ZipFile(model) as archive:
            entry = archive.read("data").decode()
        texts.append((f"{model.relative_to(ROOT)}:data", entry))
    return texts


def test_no_page_result_or_shipped_agent_names_a_path_of_a_machine():
    found = [
        f"{where}: {match.group()}..."
        for where, text in _shipped_texts()
        for match in [MACHINE_PATH.search(text)]
        if match
    ]
    assert not found, "\n".join(found)


@pytest.mark.parametrize(
    ("argv", "typed"),
    [
        (
            ["stsf-gym", "bench", "--baseline", "/srv/old", "--out", "/srv/runs/b"],
            "stsf-gym bench --baseline BASELINE --out OUT",
        ),
        (
            ["stsf-gym", "benchmark", "--agents", "follower,/m/a,/m/b", "--out", "rel/out"],
            "stsf-gym benchmark --agents follower,MODEL,MODEL2 --out rel/out",
        ),
        (
            ["stsf-gym", "sweep", "configs/sweeps/noise.yaml", "--config", "/c/w.yaml"],
            "stsf-gym sweep configs/sweeps/noise.yaml --config CONFIG",
        ),
        (
            ["stsf-gym", "evaluate", "--agent", "pretrained:sparse/ppo-truth", "--set", "a=/x/y"],
            "stsf-gym evaluate --agent pretrained:sparse/ppo-truth --set a=MODEL",
        ),
    ],
)
def test_a_command_names_its_absolute_paths(argv, typed):
    with run_context(RunContext.of(argv)):
        assert command.command_line() == typed


def test_paths_inside_a_named_one_are_named_through_it_in_a_results_file():
    argv = ["stsf-gym", "benchmark", "--agents", "/runs/a/truth", "--out", "/runs/b"]
    results = {
        "agent": "/runs/a/truth/seed-0/model.zip",
        "rows": [{"figure": "/runs/b/success.png", "other": "/runs/a/truthy"}],
        "n": 3,
    }
    assert command.portable(results, argv) == {
        "agent": "MODEL/seed-0/model.zip",
        "rows": [{"figure": "OUT/success.png", "other": "/runs/a/truthy"}],
        "n": 3,
    }


def test_a_run_records_its_command_with_out_named(run_cli, tmp_path):
    out = tmp_path / "straight"
    code, err = run_cli(
        "evaluate", "--estimators", "odometry", "--seeds", "1", "--workers", "1",
        "--world", "straight_10m", "--set", "camera.mode=fast",
        "--set", "sim.max_episode_seconds=2", "--out", str(out),
    )  # fmt: skip
    assert code == 0, err
    made_by = json.loads((out / "results.json").read_text())["provenance"]
    assert made_by["command"].endswith("--out OUT")
    assert str(tmp_path) not in json.dumps(made_by)
