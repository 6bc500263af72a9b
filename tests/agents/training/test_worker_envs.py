"""A training env whose worker dies ends the training with an error; it does not hang. A worker
that meets a full disk exits without a traceback, and the parent raises the ``ENOSPC``."""

from __future__ import annotations

import errno
import threading

import gymnasium as gym
import numpy as np
import pytest

from stsf_gym.agents.training.worker_envs import FULL_DISK_EXIT, FailFastSubprocVecEnv, WorkerDied

CLOSE_SECONDS = 60.0  # SB3's SubprocVecEnv never returns here


def full_disk() -> OSError:
    return OSError(errno.ENOSPC, "No space left on device", "monitor/train0.monitor.csv")


class FailsOnThirdStep(gym.Env):
    """Raises ``error`` (if any) at its third step."""

    observation_space = gym.spaces.Box(-1.0, 1.0, (1,), np.float32)
    action_space = gym.spaces.Box(-1.0, 1.0, (1,), np.float32)

    def __init__(self, error: Exception | None) -> None:
        self.error, self.steps = error, 0

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return np.zeros(1, np.float32), {}

    def step(self, action):
        self.steps += 1
        if self.error is not None and self.steps == 3:
            raise self.error
        return np.zeros(1, np.float32), 0.0, False, False, {}


def unbuildable() -> gym.Env:
    """An env whose construction meets a full disk (a ``Monitor`` writing its header)."""
    raise full_disk()


def closed_in_time(envs: FailFastSubprocVecEnv) -> None:
    closing = threading.Thread(target=envs.close, daemon=True)
    closing.start()
    closing.join(CLOSE_SECONDS)
    assert not closing.is_alive(), "close() hung on the dead worker"
    assert not any(process.is_alive() for process in envs.processes)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("error", "raised", "said"),
    [
        (RuntimeError("the env failed"), WorkerDied, "an env worker died during a step"),
        (full_disk(), OSError, r"No space left on device \(in an env worker\)"),
    ],
)
@pytest.mark.parametrize("failing", [0, 1])
def test_a_dead_worker_raises_from_the_step_and_close_returns(failing, error, raised, said):
    envs = FailFastSubprocVecEnv(
        [lambda rank=rank: FailsOnThirdStep(error if rank == failing else None) for rank in (0, 1)],
        "forkserver",
    )
    envs.reset()
    try:
        with pytest.raises(raised, match=said) as caught:
            for _ in range(3):
                envs.step(np.zeros((2, 1), np.float32))
    finally:
        closed_in_time(envs)
    if raised is OSError:  # the parent's ENOSPC (the command line's one line); the worker
        assert caught.value.errno == errno.ENOSPC  # exited on it, printing no traceback
        assert envs.processes[failing].exitcode == FULL_DISK_EXIT


@pytest.mark.slow
def test_a_full_disk_while_a_worker_builds_its_env_is_the_enospc():
    with pytest.raises(OSError, match="in an env worker") as caught:  # said only for a worker
        FailFastSubprocVecEnv([unbuildable, lambda: FailsOnThirdStep(None)], "forkserver")
    assert caught.value.errno == errno.ENOSPC  # that exited with FULL_DISK_EXIT, no traceback
