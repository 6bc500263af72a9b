"""A driver for tests/experiments/jobs/test_ray_addresses.py: starts a local Ray through the job
engine's runner, prints its pid once Ray runs under the watchdog, and waits to be killed."""

from __future__ import annotations

import os
import threading
import time
from pathlib import Path

from stsf_gym.experiments.jobs.backends import ray_runner
from stsf_gym.experiments.jobs.orphan_watchdog import POLL_S, descendants


def wait(job: dict) -> int:
    time.sleep(job["seconds"])
    return 0


def command_lines() -> list[str]:
    """The command lines of this process's descendants (``ray::DashboardAgent``, ...)."""
    found = []
    for pid in descendants(os.getpid()):
        try:
            found.append(Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode())
        except OSError:
            pass
    return found


if __name__ == "__main__":
    results = ray_runner(None, workers=1)(wait, [{"seconds": 600}])
    threading.Thread(target=lambda: next(iter(results)), daemon=True).start()
    while not any("orphan_watchdog" in line for line in command_lines()):  # Ray is up
        time.sleep(0.5)
    time.sleep(3 * POLL_S)  # the watchdog has noted Ray's processes
    print(os.getpid(), flush=True)
    time.sleep(600)
