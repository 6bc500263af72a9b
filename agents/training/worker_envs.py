"""Training envs in worker processes that fail when a worker dies, instead of hanging.

stable-baselines3's ``SubprocVecEnv`` keeps a step's pending replies when a worker raises:
the parent reads the replies in order, meets the dead worker's closed pipe (``EOFError``) and
leaves ``waiting`` set, so its ``close()`` then waits for a reply the live workers already
gave, forever. A training whose env raised in a worker sat there with no error.
:class:`FailFastSubprocVecEnv` raises :class:`WorkerDied` from the step instead, and closes
whatever is left of its workers within :data:`JOIN_SECONDS`.
"""

from __future__ import annotations

import contextlib

from stable_baselines3.common.vec_env import SubprocVecEnv

JOIN_SECONDS = 10.0  # a worker told to close that is still alive after this is terminated


class WorkerDied(RuntimeError):
    """An env's worker process ended in the middle of a step (its traceback is on stderr)."""


class FailFastSubprocVecEnv(SubprocVecEnv):
    """``SubprocVecEnv`` whose step raises :class:`WorkerDied` when a worker dies, and whose
    ``close`` returns whatever state its workers are in."""

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

    @staticmethod
    def _died(during: str) -> WorkerDied:
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
