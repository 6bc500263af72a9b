"""A watchdog that ends a run's helper processes when the run dies, even by ``SIGKILL``.

A local Ray instance started by a run (:func:`~stsf_gym.experiments.jobs.backends.ray_runner`)
shares the driver's fate only in part: killed with ``SIGKILL``, the driver leaves Ray's
dashboard and runtime-env agents running for minutes. :func:`start_watchdog` starts a small
process in its own session that notes the run's descendants every :data:`POLL_S` and, once the
run is gone, kills those still alive (each checked by its start time, so a reused process id is
left alone). ``python -m stsf_gym.experiments.jobs.orphan_watchdog PID`` is that process.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

POLL_S = 1.0  # s between two notes of the run's descendants


def start_watchdog() -> subprocess.Popen:
    """Watch this process; stop the watchdog with ``terminate()`` when the run ends well."""
    return subprocess.Popen(
        [sys.executable, "-m", __name__, str(os.getpid())],
        start_new_session=True,  # a Ctrl-C to the run's process group leaves it watching
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def _processes() -> dict[int, tuple[int, str]]:
    """Every process id: (parent id, start time in clock ticks since boot)."""
    found = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):  # gone meanwhile
            continue
        found[int(stat.parent.name)] = (int(fields[1]), fields[19])
    return found


def descendants(root: int) -> dict[int, str]:
    """The processes under ``root`` (children, theirs...): id -> start time."""
    table = _processes()
    found, frontier = {}, [root]
    while frontier:
        parent = frontier.pop()
        for pid, (ppid, started) in table.items():
            if ppid == parent and pid not in found:
                found[pid] = started
                frontier.append(pid)
    return found


def watch(run: int) -> None:
    """Note ``run``'s descendants until it is gone, then kill those still alive."""
    noted: dict[int, str] = {}
    while _processes().get(run) is not None:
        noted = {p: s for p, s in descendants(run).items() if p != os.getpid()}
        time.sleep(POLL_S)
    alive = _processes()
    for pid, started in noted.items():
        if pid in alive and alive[pid][1] == started:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:  # gone, or not ours
                pass


if __name__ == "__main__":
    watch(int(sys.argv[1]))
