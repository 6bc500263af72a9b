"""Ray addresses and the processes a run leaves: an address where no Ray answers is refused in one
line, and the orphan watchdog kills what a SIGKILLed run (or Ray driver) left."""

from __future__ import annotations

import pytest

from stsf_gym.validation import ConfigError


def test_an_address_where_a_service_that_is_not_ray_answers_is_refused():
    import socket
    import threading

    from stsf_gym.experiments.jobs.backends import check_ray_address

    server = socket.create_server(("127.0.0.1", 0))
    threading.Thread(target=lambda: [server.accept() for _ in range(8)], daemon=True).start()
    address = f"127.0.0.1:{server.getsockname()[1]}"
    with pytest.raises(ConfigError, match=f"^--address {address}: no Ray cluster"):
        check_ray_address(address, join_timeout_s=3.0)  # joined, late or refused: one line
    server.close()


@pytest.mark.slow
def test_address_auto_without_a_cluster_is_one_line(run_cli, tmp_path):
    pytest.importorskip("ray")
    out = tmp_path / "o"
    argv = ["--suite", "corridor", "--worlds", "1", "--agents", "follower", "--out", str(out)]
    code, err = run_cli("benchmark", *argv, "--backend", "ray", "--address", "auto")
    assert code == 2 and "--address auto: no Ray cluster to join (ConnectionError" in err
    assert not out.exists()


def _alive(pid: int) -> bool:
    from stsf_gym.experiments.jobs.orphan_watchdog import _processes

    return pid in _processes()


def test_the_watchdog_kills_what_a_killed_run_left(tmp_path):
    import os
    import signal
    import subprocess
    import sys
    import time

    code = (
        "import subprocess, sys, time\n"
        "from stsf_gym.experiments.jobs.orphan_watchdog import start_watchdog\n"
        "child = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(600)'])\n"
        "start_watchdog(); print(child.pid, flush=True); time.sleep(600)\n"
    )
    run = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    child = int(run.stdout.readline())
    time.sleep(2.5)  # the watchdog notes the child (every POLL_S)
    os.kill(run.pid, signal.SIGKILL)
    run.wait()
    for _ in range(100):  # the watchdog sees the run gone within a POLL_S
        if not _alive(child):
            break
        time.sleep(0.2)
    assert not _alive(child)


@pytest.mark.slow
def test_a_driver_killed_with_sigkill_leaves_no_ray_process():
    import os
    import signal
    import subprocess
    import sys
    import time
    from pathlib import Path

    pytest.importorskip("ray")
    from stsf_gym.experiments.jobs.orphan_watchdog import descendants

    script = Path(__file__).with_name("ray_kill_driver.py")
    driver = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True)
    assert int(driver.stdout.readline()) == driver.pid
    left = set(descendants(driver.pid))
    os.kill(driver.pid, signal.SIGKILL)
    driver.wait()
    for _ in range(150):
        if not any(_alive(pid) for pid in left):
            break
        time.sleep(0.2)
    assert not [pid for pid in left if _alive(pid)]
