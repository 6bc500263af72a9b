"""Training envs in worker processes that fail when a worker dies, instead of hanging.

stable-baselines3's ``SubprocVecEnv`` keeps a step's pending replies when a worker raises:
the parent reads the replies in order, meets the dead worker's closed pipe (``EOFError``) and
leaves ``waiting`` set, so its ``close()`` then waits for a reply the live workers already
gave, forever. A training whose env raised in a worker sat there with no error.
:class:`FailFastSubprocVecEnv` raises :class:`WorkerDied` from the step instead, and closes
whatever is left of its workers within :data:`JOIN_SECONDS`. A worker that meets a full disk
(``OSError`` ``ENOSPC``: its ``Monitor`` file) exits quietly with :data:`FULL_DISK_EXIT`, and
the parent raises that ``ENOSPC`` itself: the command line's one line for a full disk.
"""

from __future__ import annotations

import contextlib
import errno
import os
import sys
from collections.abc import Callable, Iterator
from functools import partial
from multiprocessing.connection import wait

import gymnasium as gym
from stable_baselines3.common.vec_env import SubprocVecEnv

JOIN_SECONDS = 10.0  # a worker told to close that is still alive after this is terminated
FULL_DISK_EXIT = 75  # a worker's exit status after an ENOSPC (no traceback printed)


class WorkerDied(RuntimeError):
    """An env's worker process ended in the middle of a step (its traceback is on stderr)."""


@contextlib.contextmanager
def exit_on_full_disk() -> Iterator[None]:
    """In a worker process: an ``OSError`` ``ENOSPC`` ends it with :data:`FULL_DISK_EXIT`."""
    try:
        yield
    except OSError as err:
        if err.errno != errno.ENOSPC:
            raise
        sys.exit(FULL_DISK_EXIT)  # multiprocessing ends the worker on it without a traceback


class ExitOnFullDisk(gym.Wrapper):
    """A worker's env whose ``reset``, ``step`` and ``close`` exit on a full disk
    (:func:`exit_on_full_disk`)."""

    def reset(self, **kwargs):
        """Reset the env."""
        with exit_on_full_disk():
            return self.env.reset(**kwargs)

    def step(self, action):
        """Step the env."""
        with exit_on_full_disk():
            return self.env.step(action)

    def close(self) -> None:
        """Close the env (a ``Monitor`` flushes its file)."""
        with exit_on_full_disk():
            self.env.close()


def built_exiting_on_full_disk(env_fn: Callable[[], gym.Env]) -> gym.Env:
    """``env_fn()`` (in a worker process) as an :class:`ExitOnFullDisk`."""
    with exit_on_full_disk():
        return ExitOnFullDisk(env_fn())


class FailFastSubprocVecEnv(SubprocVecEnv):
    """``SubprocVecEnv`` whose start, reset and step raise :class:`WorkerDied` when a worker
    dies (the ``ENOSPC`` when it exited on a full disk), and whose ``close`` returns whatever
    state its workers are in."""

    def __init__(self, env_fns: list[Callable[[], gym.Env]], start_method: str | None = None):
        try:
            super().__init__(
                [partial(built_exiting_on_full_disk, f) for f in env_fns], start_method
            )
        except (EOFError, ConnectionError) as err:
            died = self._died("start")
            self.close()
            raise died from err

    def reset(self):
        """The first observations; :class:`WorkerDied` when a worker's pipe closed."""
        try:
            return super().reset()
        except (EOFError, ConnectionError) as err:
            raise self._died("reset") from err

    def step_wait(self):
        """The step's replies; :class:`WorkerDied` when a worker's pipe closed."""
        try:
            return super().step_wait()
        except (EOFError, ConnectionError) as err:
            self.waiting = False  # the live workers' replies are dropped with the step
            raise self._died("step") from err

    def _died(self, during: str) -> Exception:
        """The error of a worker gone during ``during``: ``ENOSPC`` for one that exited on a
        full disk, else :class:`WorkerDied`."""
        processes = {process.sentinel: process for process in self.processes}
        ended = wait(list(processes), JOIN_SECONDS)
        if any(processes[sentinel].exitcode == FULL_DISK_EXIT for sentinel in ended):
            return OSError(errno.ENOSPC, f"{os.strerror(errno.ENOSPC)} (in an env worker)")
        return WorkerDied(f"an env worker died during a {during}; its error is printed above")

    def close(self) -> None:
        """Tell each worker to close, then join it (terminating one that does not end)."""
        if self.closed:
            return
        for remote in self.remotes:
            with contextlib.suppress(BrokenPipeError, ConnectionError, EOFError):
                remote.send(("close", None))
        for process in self.processes:
            process.join(JOIN_SECONDS)
            if process.is_alive():
                process.terminate()
                process.join()
        self.closed = True
