import json
import subprocess
import sys

import pytest

CLI = [sys.executable, "-m", "stsf_gym.cli"]


def test_demo_json_and_files(tmp_path):
    out = tmp_path / "demo"
    result = subprocess.run(
        [*CLI, "demo", "--seconds", "3", "--seed", "1", "--out", str(out), "--json"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout)  # stdout holds nothing but the JSON
    assert summary["seed"] == 1 and summary["sim_time_s"] == pytest.approx(3.0)
    assert summary["renderer"] in ("egl", "tiny")
    assert (out / "demo.png").stat().st_size > 10_000
    assert json.loads((out / "summary.json").read_text())["camera_frames"] == 16
    assert "| t (s) |" in (out / "summary.md").read_text()


@pytest.mark.parametrize(
    ("args", "message"),
    [(["--set", "camera.widht=3"], "camera.widht"), (["--seconds", "-1"], "--seconds")],
)
def test_bad_arguments_named(tmp_path, args, message):
    result = subprocess.run(
        [*CLI, "demo", "--out", str(tmp_path), *args], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 2
    assert message in result.stderr


def test_help_lists_commands():
    result = subprocess.run([*CLI, "--help"], capture_output=True, text=True)
    assert result.returncode == 0 and "demo" in result.stdout
