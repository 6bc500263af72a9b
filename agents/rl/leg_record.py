"""How a training leg ended, and how near its goal it came: what a learning curve cannot say.

A learner that declares no goal may never reach one, or reach it and not declare. The first
is a driving problem, the second a declaration problem, and they call for different cures.
:class:`LegRecord` adds to the last ``info`` of an episode (where SB3's ``Monitor`` reads its
``info_keywords``, :data:`LEG_KEYS`):

- ``outcome``: ``goal`` (every goal declared), ``collision``, ``false stop`` (a stop off the
  goal that ended the episode), or ``time limit`` (truncated);
- ``closest_m``: the least true distance from the robot to the goal current at the end (a
  leg's only goal), sampled at every step the wrapper sees (a decision, 0.5 s, on the
  RL-ready ids);
- ``in_radius``: the steps it saw with the robot within that goal's radius;
- ``false_stops``: the stops declared off their goal.

Judged at the true position, as the task judges a stop: a diagnostic for training, never an
input of the policy.
"""

from __future__ import annotations

import math

import gymnasium as gym

#: The keys :class:`LegRecord` adds to an episode's last ``info`` (Monitor ``info_keywords``).
LEG_KEYS = ("outcome", "closest_m", "in_radius", "false_stops")
OUTCOMES = ("goal", "collision", "false stop", "time limit")


class LegRecord(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """Records each episode's ending and its closest approach to the goal (see the module)."""

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.Wrapper.__init__(self, env)
        self._closest, self._in_radius, self._goal = math.inf, 0, 0

    def reset(self, **kwargs):
        """Reset the env and the leg's record."""
        observation, info = self.env.reset(**kwargs)
        self._closest, self._in_radius, self._goal = math.inf, 0, 0
        return observation, info

    def step(self, action):
        """Step the env; at the episode's end, add the leg's record to ``info``."""
        observation, reward, terminated, truncated, info = self.env.step(action)
        task = self.env.unwrapped.task  # type: ignore[attr-defined]
        reached = int(info["goals_reached"])
        if reached != self._goal and not info["success"]:  # a goal declared: the next one's
            self._closest, self._in_radius = math.inf, 0
        self._goal = reached
        distance = task.distance_to_goal(info["true_pose"])  # the last goal once all are done
        self._closest = min(self._closest, distance)
        self._in_radius += int(distance <= task.goal_radius)
        if terminated or truncated:
            info = {**info, **self.record(info, truncated)}
        return observation, reward, terminated, truncated, info

    def record(self, info: dict, truncated: bool) -> dict:
        """The leg's :data:`LEG_KEYS` at its last step ``info``."""
        if info["success"]:
            outcome = "goal"
        elif info["collision"]:
            outcome = "collision"
        elif truncated:
            outcome = "time limit"
        else:
            outcome = "false stop"
        stops = self.env.unwrapped.task.stops  # type: ignore[attr-defined]
        return {
            "outcome": outcome,
            "closest_m": self._closest,
            "in_radius": self._in_radius,
            "false_stops": sum(not stop.success for stop in stops),
        }
