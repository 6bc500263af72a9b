"""How a learner declares arrival during training: the designs the pilot compares.

The evaluation task never changes (a declared stop off its goal ends the route as a failure,
judged at the true position: :class:`~stsf_gym.envs.task.PathTask`). What a design changes is
the training legs and the action a policy emits:

- ``stop``: the task as it is evaluated, with the continuous STOP entry (``task.stop_action``,
  above 0 declares). A fresh Gaussian policy declares at half its decisions, so nearly every
  leg ends in a false stop within a few decisions (DESIGN.md, facts of 2026-11-28).
- ``stop-goes-on``: the same action; on training legs a stop off the goal costs
  :data:`GOES_ON_FALSE_STOP` and the leg goes on (``task.false_stop_ends: false``), so trying
  to declare is not ended for trying and a declaration near the goal is met by chance.
- ``discrete``: Habitat PointNav's discrete actions (:data:`DISCRETE_ACTIONS`: STOP is one of
  seven), on legs where a false stop goes on, as above.

:data:`GOES_ON_FALSE_STOP` = -1: a tenth of the goal bonus (``reward.goal`` = 10), the cost of
100 s of the task's time (``reward.time`` = -0.01/s), ten metres of progress short of a leg's
worth. A declaration off the goal then never pays (it costs, and changes nothing), a learner
may try about ten declarations for each it gets right before trying stops paying nothing,
and an agent that declares at every decision of a 10 m leg (160 decisions) loses sixteen
times what the leg's goal pays: the return's optimum stays the task's.
"""

from __future__ import annotations

from dataclasses import dataclass

import gymnasium as gym
import numpy as np
from gymnasium import spaces

#: reward.false_stop of the training legs where a false stop goes on (see the module).
GOES_ON_FALSE_STOP = -1.0
#: The RL-ready ids' design, and plain RL's on a suite in ``stsf-gym train`` (docs/rl.md).
DEFAULT_DECLARATION = "stop-goes-on"

#: Habitat-style discrete actions: (name, v in m/s, w in rad/s, declares). Forward at the
#: paper's 0.122 m/s is 6 cm a 0.5 s decision, a quarter of the 0.25 m goal radius; turns at
#: the follower's 0.6 rad/s (17 deg a decision) and arcs at half of it (a 0.4 m turning radius,
#: inside a corridor bend's); ``wait`` stands still without declaring.
DISCRETE_ACTIONS: tuple[tuple[str, float, float, bool], ...] = (
    ("stop", 0.0, 0.0, True),
    ("forward", 0.122, 0.0, False),
    ("forward-left", 0.122, 0.3, False),
    ("forward-right", 0.122, -0.3, False),
    ("left", 0.0, 0.6, False),
    ("right", 0.0, -0.6, False),
    ("wait", 0.0, 0.0, False),
)


@dataclass(frozen=True)
class Declaration:
    """A declaration design: the training legs' task and reward over the suite's, and whether
    the action is discrete."""

    name: str
    goes_on: bool  # a false stop on a training leg costs and the leg goes on
    discrete: bool

    def training_env(self) -> dict:
        """The env settings the design adds to the training legs."""
        if not self.goes_on:
            return {}
        return {"task": {"false_stop_ends": False}, "reward": {"false_stop": GOES_ON_FALSE_STOP}}


DECLARATIONS = {
    d.name: d
    for d in (
        Declaration("stop", goes_on=False, discrete=False),
        Declaration("stop-goes-on", goes_on=True, discrete=False),
        Declaration("discrete", goes_on=True, discrete=True),
    )
}


def declaration(name: str) -> Declaration:
    """The design called ``name``; ``ValueError`` naming the known ones otherwise."""
    if name not in DECLARATIONS:
        raise ValueError(f"unknown declaration {name!r}; known: {', '.join(DECLARATIONS)}")
    return DECLARATIONS[name]


class DiscreteActions(gym.ActionWrapper, gym.utils.RecordConstructorArgs):
    """``Discrete(7)`` over an env whose action is ``[v, w, stop]`` (its ``action_layout``):
    action ``i`` drives :data:`DISCRETE_ACTIONS` ``[i]``, scaled by the robot's top speed and
    yaw rate; :attr:`action_names` names them."""

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.ActionWrapper.__init__(self, env)
        layout = env.get_wrapper_attr("action_layout")
        if tuple(layout.names) != ("v", "w", "stop"):
            raise ValueError(f"DiscreteActions needs the action [v, w, stop], got {layout.names}")
        robot = env.unwrapped.config.robot  # type: ignore[attr-defined]
        self.action_names = tuple(name for name, *_ in DISCRETE_ACTIONS)
        self._table = np.array(
            [
                [v / robot.max_speed, w / robot.max_yaw_rate, 1.0 if stop else -1.0]
                for _, v, w, stop in DISCRETE_ACTIONS
            ],
            np.float32,
        )
        self.action_space = spaces.Discrete(len(DISCRETE_ACTIONS))

    def action(self, action) -> np.ndarray:
        """The Box action of discrete ``action``."""
        index = int(np.asarray(action).reshape(()))
        if not 0 <= index < len(self._table):
            raise ValueError(f"action must be 0..{len(self._table) - 1}, got {action!r}")
        return self._table[index].copy()
