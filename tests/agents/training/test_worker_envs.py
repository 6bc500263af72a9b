"""A training env whose worker dies ends the training with an error; it does not hang."""

from __future__ import annotations

import threading

import gymnasium as gym
import numpy as np
import pytest

from stsf_gym.agents.training.worker_envs import FailFastSubprocVecEnv, WorkerDied

CLOSE_SECONDS = 60.0  # SB3's SubprocVecEnv never returns here


class FailsOnThirdStep(gym.Env):
    """Raises at its third step when ``fails``."""

    observation_space = gym.spaces.Box(-1.0, 1.0, (1,), np.float32)
    action_space = gym.spaces.Box(-1.0, 1.0, (1,), np.float32)

    def __init__(self, fails: bool) -> None:
        self.fails, self.steps = fails, 0

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return np.zeros(1, np.float32), {}

    def step(self, action):
        self.steps += 1
        if self.fails and self.steps == 3:
            raise RuntimeError("the env failed")
        return np.zeros(1, np.float32), 0.0, False, False, {}


@pytest.mark.slow
@pytest.mark.parametrize("failing", [0, 1])
def test_a_dead_worker_raises_from_the_step_and_close_returns(failing):
    envs = FailFastSubprocVecEnv(
        [lambda rank=rank: FailsOnThirdStep(rank == failing) for rank in range(2)], "forkserver"
    )
    envs.reset()
    try:
        with pytest.raises(WorkerDied, match="an env worker died during a step"):
            for _ in range(3):
                envs.step(np.zeros((2, 1), np.float32))
    finally:
        closing = threading.Thread(target=envs.close, daemon=True)
        closing.start()
        closing.join(CLOSE_SECONDS)
    assert not closing.is_alive(), "close() hung on the dead worker"
    assert not any(process.is_alive() for process in envs.processes)
