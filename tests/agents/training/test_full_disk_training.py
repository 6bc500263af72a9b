"""``stsf-gym train`` on a full disk (``OSError`` ``ENOSPC``): in a checkpoint's save or in an
env worker's ``Monitor`` file, one line and exit status 1, no traceback; the checkpoints saved
before stay valid and the same command resumes from them; the run's CSV logs keep no row cut
short."""

from __future__ import annotations

import errno
import json
import os
from pathlib import Path

import pytest

import stsf_gym.agents.training.checkpoints as checkpoints
from stsf_gym.agents.training.training_log import EPISODES_CSV, append_row, drop_rows_after

TRAIN = ["train", "--algo", "ppo", "--estimator", "truth", "--timesteps", "128"]
TRAIN += ["--set", "n_steps=32", "--set", "batch_size=32", "--set", "n_epochs=1"]
TRAIN += ["--set", "env.sim.max_episode_seconds=3", "--set", "env.camera.enabled=false"]
FULL = "the disk is full"
SAID = "every file saved before stays valid (files are written whole or not at all): free space "
SAID += "and rerun with the same --out to resume"


def one_error_line(err: str) -> str:
    """The one error line of ``err``, its last (a progress bar may be drawn before)."""
    errors = [line for line in err.splitlines() if "error:" in line]
    assert errors == [err.strip().splitlines()[-1]] and "Traceback" not in err, err
    return errors[0]


@pytest.mark.slow
def test_a_full_disk_saving_a_checkpoint_is_one_line_and_the_run_resumes(
    run_cli, tmp_path, monkeypatch
):
    saves, write = [], checkpoints.write_atomic

    def full_at_the_second(path, data):
        saves.append(path)
        if len(saves) == 2:
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        return write(path, data)

    monkeypatch.setattr(checkpoints, "write_atomic", full_at_the_second)
    code, err = run_cli(*TRAIN, "--n-envs", "1", "--out", str(tmp_path))
    assert code == 1
    assert one_error_line(err) == f"stsf-gym train: error: {FULL} writing {saves[1]}; {SAID}"
    kept = sorted(p.name for p in (tmp_path / "checkpoints").iterdir())
    assert kept == ["model_32_steps.zip"]  # the first checkpoint whole, nothing of the second
    monkeypatch.setattr(checkpoints, "write_atomic", write)
    code, err = run_cli(*TRAIN, "--n-envs", "1", "--out", str(tmp_path))
    assert code == 0, err
    summary = json.loads((tmp_path / "train.json").read_text())
    assert summary["resumed_from"] == 32 and summary["timesteps"] == 128  # from the first


@pytest.mark.slow
def test_a_full_disk_in_an_env_worker_is_one_line(run_cli, tmp_path):
    (tmp_path / "monitor").mkdir()  # the second worker's Monitor file: writes meet ENOSPC
    os.symlink("/dev/full", tmp_path / "monitor" / "train1.monitor.csv")
    code, err = run_cli(*TRAIN, "--n-envs", "2", "--out", str(tmp_path))
    assert code == 1
    assert one_error_line(err) == f"stsf-gym train: error: {FULL}; {SAID}"


def no_space(path: Path) -> OSError:
    return OSError(errno.ENOSPC, "No space left on device", str(path))


class HalfWritten:
    """A file whose write puts down half its text, then meets a full disk."""

    def __init__(self, real) -> None:
        self.real = real

    def __enter__(self) -> HalfWritten:
        return self

    def __exit__(self, *exc) -> None:
        self.real.close()

    def write(self, text: str) -> None:
        self.real.write(text[: len(text) // 2])
        self.real.flush()
        raise no_space(Path(self.real.name))


def test_a_row_cut_short_by_a_full_disk_leaves_the_csv_as_it_was(tmp_path, monkeypatch):
    path, header = tmp_path / EPISODES_CSV, ["timesteps", "reward"]
    append_row(path, header, [32, 1.5])
    before, real_open = path.read_bytes(), Path.open
    monkeypatch.setattr(Path, "open", lambda *a, **k: HalfWritten(real_open(*a, **k)))
    with pytest.raises(OSError, match="No space left"):
        append_row(path, header, [64, 2.5])
    monkeypatch.undo()
    assert path.read_bytes() == before


def test_a_resume_that_meets_a_full_disk_keeps_the_csv_whole(tmp_path, monkeypatch):
    path, header = tmp_path / EPISODES_CSV, ["timesteps", "reward"]
    for steps in (32, 64):
        append_row(path, header, [steps, 1.0])
    before = path.read_bytes()

    def full(src, dst):
        raise no_space(Path(dst))

    monkeypatch.setattr(os, "replace", full)
    with pytest.raises(OSError, match="No space left"):
        drop_rows_after(path, 32)
    assert path.read_bytes() == before and sorted(os.listdir(tmp_path)) == [EPISODES_CSV]
    monkeypatch.undo()
    drop_rows_after(path, 32)
    assert path.read_text().splitlines() == ["timesteps,reward", "32,1.0"]
