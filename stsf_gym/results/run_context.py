"""The run a result belongs to: its command line and the code it loaded beyond this process.

A :class:`RunContext` holds what a results file's provenance needs from the run that made it
and that no single module sees: the command as the user typed it, the package modules its
workers loaded (each job's worker reports them, :mod:`~stsf_gym.experiments.jobs.backends`)
and the package data files it read (a shipped agent's models). The CLI makes one per command
and enters it (:func:`run_context`); the job engine notes its workers' modules into the one
its jobs ran under, and :func:`~stsf_gym.results.provenance.provenance` reads it.

The context is carried by a :class:`~contextvars.ContextVar`, not passed as an argument:
those who note into it sit deep below every API call (an agent's models are found while its
name is resolved, an env's worker processes are asked inside the trainer), and passing it
down would add a parameter to every function between. A ``with run_context(...)`` block
scopes it, so two runs in one process (a test session) see nothing of each other's. Code run
outside any block (a library call, a job's worker process) shares the process's own context,
as one run.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field


@dataclass(frozen=True, eq=False)
class RunContext:
    """One run: its ``command`` (argv, None: this process's ``sys.argv``), the package modules
    its workers loaded and the package data files it read (relative paths, see
    :func:`~stsf_gym.results.code_identity.loaded_modules`); the sets only grow."""

    command: tuple[str, ...] | None = None
    worker_modules: set[str] = field(default_factory=set)
    data_files: set[str] = field(default_factory=set)

    @classmethod
    def of(cls, argv: Sequence[str]) -> RunContext:
        """A fresh run of the command ``argv``."""
        return cls(tuple(argv))

    def argv(self) -> list[str]:
        """The command of this run as its words."""
        return list(self.command if self.command is not None else sys.argv)

    def note_worker_modules(self, modules: Iterable[str]) -> None:
        """Count ``modules`` (relative paths a worker reported) as code this run loaded."""
        self.worker_modules.update(modules)

    def note_data_files(self, paths: Iterable[str]) -> None:
        """Count the package files ``paths`` (relative paths) as code this run loaded."""
        self.data_files.update(paths)


#: The context of code run outside any :func:`run_context` block: this process, as one run.
PROCESS_RUN = RunContext()
_current: ContextVar[RunContext] = ContextVar("run_context", default=PROCESS_RUN)


def current_run() -> RunContext:
    """The run being made: the innermost :func:`run_context` block's, else :data:`PROCESS_RUN`."""
    return _current.get()


@contextmanager
def run_context(run: RunContext | None = None) -> Iterator[RunContext]:
    """``run`` (default a fresh one of this process's ``sys.argv``) as the current run inside
    the block, the one before it again after."""
    run = RunContext() if run is None else run
    token = _current.set(run)
    try:
        yield run
    finally:
        _current.reset(token)
