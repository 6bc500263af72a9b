"""The command line of a run, as a user would type it on any machine.

A run's command is its context's (:class:`~stsf_gym.results.run_context.RunContext`: the
CLI's ``argv``; a run not started by the CLI records ``sys.argv``); a results file shows it
with every absolute path named (``OUT``, ``BASELINE``, ``CONFIG``, ``MODEL``: :func:`portable`),
so no page or result carries this machine's paths.
"""

from __future__ import annotations

import itertools
import os
import re
import shlex
from collections.abc import Sequence
from typing import Any, TypeVar

from stsf_gym.results.run_context import current_run

T = TypeVar("T")


def command_line() -> str:
    """The command of the current run as a user would type it anywhere: each absolute path
    named (:func:`portable`), as a shell would take it."""
    return shlex.join(portable(current_run().argv()))


#: The names of the absolute paths given to these options in a recorded command.
PATH_NAMES = {"--out": "OUT", "--baseline": "BASELINE", "--config": "CONFIG"}
#: An absolute path inside a command-line word (after a start, ``=``, ``,`` or ``:``).
ABSOLUTE = re.compile(r"(?:(?<=^)|(?<=[=,:]))/[^\s,=:/][^\s,=:]*")


def path_names(argv: Sequence[str]) -> dict[str, str]:
    """``{absolute path: name}`` of the paths in ``argv``: those of :data:`PATH_NAMES`'s
    options by the option, every other one (an agent's model or training folder) ``MODEL``,
    ``MODEL2``, ... in order; a path inside a named one is named through it (``OUT/a.json``)."""
    names = {
        os.path.normpath(value): PATH_NAMES[flag]
        for flag, value in itertools.pairwise(argv)
        if flag in PATH_NAMES and os.path.isabs(value)
    }
    for word in argv:
        for path in ABSOLUTE.findall(word):
            path = os.path.normpath(path)
            if not any(path == n or path.startswith(n + "/") for n in names):
                count = sum(name.startswith("MODEL") for name in names.values())
                names[path] = "MODEL" if count == 0 else f"MODEL{count + 1}"
    return names


def portable(value: T, argv: Sequence[str] | None = None) -> T:
    """``value`` (a string, or lists and dicts of them) with every absolute path of the command
    ``argv`` (default the current run's) replaced by its name (:func:`path_names`): what a
    results file or a page shows, the same on every machine."""
    names = path_names(current_run().argv() if argv is None else argv)
    ordered = sorted(names.items(), key=lambda item: -len(item[0]))

    def rename(text: str) -> str:
        for path, name in ordered:
            text = re.sub(re.escape(path) + r"(?=$|[/\s,=:\"'])", name, text)
        return text

    def walk(item: Any) -> Any:
        if isinstance(item, str):
            return rename(item)
        if isinstance(item, list):
            return [walk(v) for v in item]
        if isinstance(item, dict):
            return {k: walk(v) for k, v in item.items()}
        return item

    return walk(value)
