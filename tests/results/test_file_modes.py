"""Files written atomically get the mode the user's umask gives new files (a shared server's
colleagues can read results and models when the umask lets them), not ``tempfile``'s 0o600."""

import os
import stat

import numpy as np
import pytest

from stsf_gym.io import save_figure, write_atomic, write_json
from stsf_gym.recording import ros_messages as ros
from stsf_gym.recording import topics
from stsf_gym.recording.mcap_writer import McapLogWriter
from stsf_gym.video import VideoWriter


@pytest.fixture(params=[0o022, 0o077, 0o002])
def umask(request):
    old = os.umask(request.param)
    yield request.param
    os.umask(old)


def _mode(path) -> int:
    return stat.S_IMODE(os.stat(path).st_mode)


def _write_every_kind(folder) -> list:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, _ = plt.subplots()
    paths = [
        write_atomic(folder / "model.zip", b"PK\x03\x04"),
        write_json(folder / "results.json", {"success_rate": {"mean": 1.0}}),
        save_figure(fig, folder / "figure.png"),
    ]
    plt.close(fig)
    with VideoWriter(folder / "clip", fps=5, mp4=False) as video:
        video.append(np.zeros((8, 8, 3), np.uint8))
    log = McapLogWriter(folder / "own.mcap")
    log.write(topics.WHEEL_TICKS, 1_000, ros.joint_state(1_000, topics.WHEELS, [0, 0]))
    log.close()
    return [*paths, video.path, log.path]


def test_every_output_file_gets_the_umasks_mode(tmp_path, umask):
    paths = _write_every_kind(tmp_path)
    plain = tmp_path / "plain.txt"
    plain.write_text("as open() makes a file")
    assert {p.name: _mode(p) for p in paths} == dict.fromkeys(
        (p.name for p in paths), 0o666 & ~umask
    )
    assert _mode(plain) == 0o666 & ~umask
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [p.name for p in paths] + ["plain.txt"]
    )  # no temporary left behind


def test_a_failed_write_leaves_neither_file_nor_temporary(tmp_path):
    class Unwritable:
        pass

    with pytest.raises(TypeError):
        write_atomic(tmp_path / "results.json", Unwritable())
    assert list(tmp_path.iterdir()) == []
