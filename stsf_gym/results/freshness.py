"""Whether a stored result is current: derived from the code it ran with, never declared.

Every job the engine stores records the package modules its process had loaded when it
finished, each with its :func:`~stsf_gym.results.behaviour.code_digest` (what the module
computes: docstrings and comments left out), beside the digest of its resolved configuration.
The row stays current while each module it lists computes what it did: an edit of one (a
scoring change, a new default in code) makes the rows that loaded that module stale and no
others, and a report made from the rows (a benchmark's scores, its intervals) is recomputed at
every run anyway. A worker's modules accumulate over the jobs it runs, so a row may list a
module its job did not need: a rerun then does more than it must, never less.

The one override is :data:`EQUIVALENT`: earlier digests of a module declared to compute what
today's does, for a rewrite proved bit-equal by the golden episodes
(``tests/behaviour/test_step_equality.py``, so only modules of the subsystems they pin:
``tests/results/test_freshness.py`` checks it).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from stsf_gym.results.behaviour import code_digest
from stsf_gym.results.code_identity import package_file

#: ``{relative path: earlier code digests}`` declared to compute what today's module does.
EQUIVALENT: dict[str, frozenset[str]] = {}


class CurrentCode:
    """The code digests of the package's modules as they are now, each file read once."""

    def __init__(self) -> None:
        self._digests: dict[str, str | None] = {}

    def digest(self, path: str) -> str | None:
        """:func:`code_digest` of the package's ``path`` now; None when it is gone."""
        if path not in self._digests:
            try:
                file = package_file(path)
            except KeyError:  # not a folder of the package
                file = None
            self._digests[path] = code_digest(file) if file and file.is_file() else None
        return self._digests[path]

    def record(self, modules: Iterable[str]) -> dict[str, str]:
        """``{path: digest}`` of the ``modules`` (relative paths) a job ran with."""
        found = {path: self.digest(path) for path in sorted(set(modules))}
        return {path: digest for path, digest in found.items() if digest is not None}

    def changed(self, record: Mapping[str, str]) -> list[str]:
        """The modules of ``record`` that compute otherwise now (edited, or gone)."""
        return [
            path
            for path, digest in record.items()
            if self.digest(path) != digest and digest not in EQUIVALENT.get(path, ())
        ]

    def is_current(self, record: Mapping[str, str]) -> bool:
        """Whether every module of ``record`` computes what it did (an empty one never)."""
        return bool(record) and not self.changed(record)
