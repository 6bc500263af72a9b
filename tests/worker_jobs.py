"""Jobs that tests run in worker processes, kept apart from the tests so that a worker imports
only this module and what its job imports (``tests/test_provenance.py``)."""

from __future__ import annotations

import importlib


def import_module(job: dict) -> int:
    """Import the module ``job["module"]`` in the worker; return ``job["n"]``."""
    importlib.import_module(job["module"])
    return job["n"]
