"""The residual learner decides near the goals only; the follower drives alone between them.

On a sparse route of about 400 decisions the follower's failures are decided in the few
metres before each goal: where it declares, whether it would have waited or turned to a
board. A correction learnt from the route's return must find those decisions among hundreds
whose correction changes nothing that the reward sees, and the advantages of a 400-decision
return are too noisy to steer by (the residual campaign's first seed: docs/rl.md).
:class:`LearnerNearGoals` sits over the decision interval and takes the policy's decisions
only while the estimated position is within ``acts_within`` metres of the current goal
(:attr:`~stsf_gym.agents.rl.residual.ResidualFollower.near_goal`); elsewhere the follower
drives alone, as the zero correction drives, and its decisions are folded into the
learner's next one: their rewards summed into its reward, their count in
``info["follower_decisions"]``, their control steps in ``info["control_steps"]`` (the
learner's decision's and theirs, as the training log counts the time driven). The learner's
episode is then the tens of decisions around each goal, and its return is what they earned.

A decision taken where the learner does not act (an episode's first, from a start far from
the goal) is driven as the zero correction. The untrained learner therefore still drives the
follower's episode step for step. The distance is the estimate's, as every input is: the
truth never decides who drives.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np


class LearnerNearGoals(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """The policy's decisions near the goals only (see the module). Wraps a decision
    interval over a :class:`~stsf_gym.agents.rl.residual.ResidualFollower`."""

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.Wrapper.__init__(self, env)
        shape = self.action_space.shape
        assert shape is not None, self.action_space
        self._neutral = np.zeros(shape, np.float32)  # the zero correction: the follower's action

    def _learner_acts(self) -> bool:
        return bool(self.env.get_wrapper_attr("near_goal"))

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Reset the env; ``info["follower_decisions"]`` 0."""
        obs, info = self.env.reset(seed=seed, options=options)
        return obs, {**info, "follower_decisions": 0}

    def step(self, action):
        """The policy's decision (the follower's where it does not act), then the follower's
        alone until the learner acts again or the episode ends."""
        if not self._learner_acts():
            action = self._neutral
        obs, total, terminated, truncated, info = self.env.step(action)
        total, alone, steps = float(total), 0, int(info["control_steps"])
        while not (terminated or truncated or self._learner_acts()):
            obs, reward, terminated, truncated, info = self.env.step(self._neutral)
            total, alone = total + float(reward), alone + 1
            steps += int(info["control_steps"])
        done = {"follower_decisions": alone, "control_steps": steps}
        return obs, total, terminated, truncated, {**info, **done}
