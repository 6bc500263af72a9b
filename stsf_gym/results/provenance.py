"""What made a result: the code, the packages, the resolved configuration, the seeds, the command.

Every ``results.json``, ``train.json``, model file and recording carries a :func:`provenance`
record, put together from its parts (those of the run it belongs to:
:mod:`~stsf_gym.results.run_context`): the command line (:mod:`~stsf_gym.results.command`), the
code and packages (:mod:`~stsf_gym.results.code_identity`) and the configuration as JSON
(:mod:`~stsf_gym.results.fingerprint`, which also stamps the cached units of work). The
machine's speed at the time of a run is :mod:`~stsf_gym.results.machine_speed`'s.
"""

from __future__ import annotations

import json
import platform
from collections.abc import Iterable, Mapping
from typing import Any

from stsf_gym.results.code_identity import code_version, package_versions, timed_code
from stsf_gym.results.command import command_line
from stsf_gym.results.fingerprint import canonical


def provenance(
    config: Mapping[str, Any] | None = None,
    seeds: Iterable[int] | None = None,
    timed: bool = False,
) -> dict[str, Any]:
    """The record a results file carries: code, packages, Python, platform, the fully resolved
    ``config``, the ``seeds`` and the command line; for ``timed`` results (speed figures) also
    what the loaded code computes (:func:`timed_code`)."""
    code = code_version()
    if timed:
        code["timed_code"] = timed_code(code["loaded_code"])
    return {
        "stsf_gym": code,
        "packages": package_versions(),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "command": command_line(),
        "seeds": sorted(set(seeds)) if seeds is not None else None,
        "config": json.loads(json.dumps(config or {}, default=canonical)),
    }
