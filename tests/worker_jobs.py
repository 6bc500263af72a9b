"""Jobs that tests run in worker processes, kept apart from the tests so that a worker imports
only this module and what its job imports (``tests/results/test_provenance.py``)."""

from __future__ import annotations

import importlib
import os
import time
from pathlib import Path


def import_module(job: dict) -> int:
    """Import the module ``job["module"]`` in the worker; return ``job["n"]``."""
    importlib.import_module(job["module"])
    return job["n"]


def note_pid_and_wait(job: dict) -> None:
    """Write this worker's pid to ``job["pid_file"]``, then wait for ``job["seconds"]``."""
    Path(job["pid_file"]).write_text(str(os.getpid()))
    time.sleep(job["seconds"])
