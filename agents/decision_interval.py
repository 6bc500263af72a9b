"""A policy that decides every ``k`` control steps, while the estimators see every step.

:class:`DecisionInterval` sits outside :class:`~stsf_gym.wrappers.PoseEstimateWrapper` (its
camera pointing and the policy's observation), so the estimator updates on every sensor reading
at the control rate; only the policy's decisions are spaced out, as highway-env runs its policy
at 1 Hz over a 15 Hz simulation. The interval is a physical choice (``configs/agents/*.yaml``,
``decision_steps``): see :data:`DEFAULT_DECISION_STEPS`.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from stsf_gym.envs.action_layout import numeric_action

#: Control steps (0.1 s each) per decision: 0.5 s. At the paper's 0.122 m/s the robot drives
#: 6 cm between decisions, a quarter of the 0.25 m goal radius, so a policy can place its STOP
#: inside the radius; at the follower's 0.6 rad/s a decision turns at most 17 deg, under the
#: 20 deg its pure pursuit steers by on a corridor bend in half a second. A 24 m route is then
#: about 400 decisions, inside Habitat PointNav's 500 (1 s would be 12 cm and 34 deg: a stop
#: could no longer be placed to a quarter of the radius, nor a turn followed without overshoot).
DEFAULT_DECISION_STEPS = 5


class DecisionInterval(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """Hold each action for ``steps`` control steps; the step's reward is their sum.

    The held action's ``stop`` entry (the action layout's, ``task.stop_action``) acts on the
    first step only: a declared stop is one declaration, not one per held step. The episode's
    end cuts the hold short. ``info["control_steps"]`` tells how many steps were taken (0 at
    the reset, so the key is there from the episode's start).
    """

    def __init__(self, env: gym.Env, steps: int = DEFAULT_DECISION_STEPS) -> None:
        if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
            raise ValueError(f"decision_steps must be a whole number of at least 1, got {steps!r}")
        gym.utils.RecordConstructorArgs.__init__(self, steps=steps)
        gym.Wrapper.__init__(self, env)
        self.steps = steps
        layout = env.get_wrapper_attr("action_layout")
        self._stop = layout.index("stop") if "stop" in layout else None

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Reset the env; ``info["control_steps"]`` 0."""
        obs, info = self.env.reset(seed=seed, options=options)
        return obs, {**info, "control_steps": 0}

    def step(self, action):
        """Apply ``action`` for up to :attr:`steps` control steps."""
        action = numeric_action(action).astype(np.float32)  # a copy; a bool or str refused
        if action.shape != self.action_space.shape:  # the held entries are indexed below
            raise ValueError(
                f"action must have shape {self.action_space.shape}, got {action.shape}"
            )
        total, taken = 0.0, 0
        while True:
            obs, reward, terminated, truncated, info = self.env.step(action)
            total, taken = total + float(reward), taken + 1
            if terminated or truncated or taken == self.steps:
                break
            if self._stop is not None:
                action[self._stop] = -1.0
        info["control_steps"] = taken
        return obs, total, terminated, truncated, info
