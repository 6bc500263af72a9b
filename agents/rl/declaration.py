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
- ``stop-graded``: as ``stop-goes-on``, but a false stop costs the progress reward of the
  distance it falls short of the goal (``reward.progress`` per metre, true distance), at most
  :data:`GOES_ON_FALSE_STOP` (:class:`GradedFalseStop`): a stop nearer the goal costs less,
  so the return tells a learner which way a declaration would have paid.
- ``discrete``: Habitat PointNav's discrete actions (:data:`DISCRETE_ACTIONS`: STOP is one of
  seven), on legs where a false stop goes on, as above.
- ``stop-cheap`` and ``discrete-cheap``: ``stop-goes-on`` and ``discrete`` with a false stop
  costing :data:`CHEAP_FALSE_STOP` (-0.1) instead.
- ``stop-cheap-first``: ``stop-cheap`` until a training env's last :data:`WEAN_LEGS` legs
  succeed at :data:`WEAN_SUCCESS`, then the task's own rule on its legs (a false stop ends the
  leg at the task's ``reward.false_stop``; :class:`WeanedFalseStop`).

:data:`GOES_ON_FALSE_STOP` = -1: a tenth of the goal bonus (``reward.goal`` = 10), the cost of
100 s of the task's time (``reward.time`` = -0.01/s), ten metres of progress short of a leg's
worth. A declaration off the goal then never pays (it costs, and changes nothing), a learner
may try about ten declarations for each it gets right before trying stops paying nothing,
and an agent that declares at every decision of a 10 m leg (160 decisions) loses sixteen
times what the leg's goal pays: the return's optimum stays the task's.

Measured, that cost suppresses the STOP before it is learnt (``discrete``, 40,960 decisions,
docs/rl.md): the share of legs that came within the radius rose from 0.04 to 0.74-0.82 while
the share of those that declared there fell from 1.0 to 0, and false stops from 9 a leg to
0.4: nine false stops a leg at -1 outweigh the rare goal, so the policy stops declaring
everywhere before it learns where declaring pays. :data:`CHEAP_FALSE_STOP` is fixed from that
balance. A fresh policy passing through a goal spends ``k`` = 8 decisions within the 0.25 m
radius (0.5 m at 0.122 m/s, 0.5 s a decision) on a leg of at most ``N`` = 164 decisions (10 m):
declaring more often pays while ``c * N < goal * k`` (c < 0.49), and declaring at every
decision still loses to never declaring while ``c * N > goal`` (c > 0.061). -0.1 sits five
times below the first bound and above the second; any cost above 0 keeps the optimum the task.

Measured, a cheap false stop teaches the STOP and also that a declaration just short of the
goal costs next to nothing (``discrete-cheap``: 0.98 of its last training legs, 1.6 false
stops a leg, and on full val routes, where any false stop ends the route, 4 of 20 ended so).
``stop-cheap-first`` keeps the cheap cost only while it is needed: to find the STOP. Once a
training env's last :data:`WEAN_LEGS` = 50 legs (about two updates' worth of legs at 1,024
decisions an env) succeed at :data:`WEAN_SUCCESS` = 0.8, four legs in five reach the goal and
declare there, and from then on a false stop there is what it is on a route: the end, at the
task's cost. Ending one leg in five still leaves the learner most of its goals to learn from
(the STOP was suppressed under a dear false stop when 1 leg in 30 reached a goal: the
``discrete`` unit). Each env weans itself from its own legs, so a user's script needs no
callback; a resumed run's new envs wean again after their first 50 legs.

Measured, ``stop-cheap-first`` weaned too soon (docs/rl.md): its envs reached 0.8 of legs
while the STOP still fired 26-30 times a leg on the way, so once weaned 0.9 of legs ended at
their first false stop and the STOP was suppressed again. Success counts the legs that reach
their goal, not the false stops on the way, and it is the false stops the task's rule ends.
``stop-cheap-rare`` weans only when, besides that success, ending a leg at its first false
stop would end at most ``1 - WEAN_SUCCESS`` of legs: with false stops arriving as a Poisson
count of mean ``m`` a leg, a leg holds none with probability ``exp(-m)``, so the env's last
:data:`WEAN_LEGS` legs must average at most :data:`WEAN_FALSE_STOPS` = ``-ln 0.8`` = 0.22
false stops. Weaned then, the dear false stop removes no more legs than the success rule
already allows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import gymnasium as gym
import numpy as np
from gymnasium import spaces

#: reward.false_stop of the training legs where a false stop goes on (see the module).
GOES_ON_FALSE_STOP = -1.0
#: The ``-cheap`` designs' false stop: inside the window the module derives.
CHEAP_FALSE_STOP = -0.1
#: ``stop-cheap-first``: legs an env's weaning looks back over, and the success they need.
WEAN_LEGS = 50
WEAN_SUCCESS = 0.8
#: ``stop-cheap-rare``: the most false stops a leg (mean over those legs) it weans at.
WEAN_FALSE_STOPS = -math.log(WEAN_SUCCESS)
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
    graded: bool = False  # that cost graded by the distance to the goal (GradedFalseStop)
    false_stop: float = GOES_ON_FALSE_STOP  # what a false stop that goes on costs
    weaned: bool = False  # the task's rule once the legs succeed (WeanedFalseStop)
    wean_false_stops: float = math.inf  # and once false stops a leg are at most this

    def training_env(self) -> dict:
        """The env settings the design adds to the training legs."""
        if not self.goes_on:
            return {}
        return {"task": {"false_stop_ends": False}, "reward": {"false_stop": self.false_stop}}


DECLARATIONS = {
    d.name: d
    for d in (
        Declaration("stop", goes_on=False, discrete=False),
        Declaration("stop-goes-on", goes_on=True, discrete=False),
        Declaration("stop-graded", goes_on=True, discrete=False, graded=True),
        Declaration("discrete", goes_on=True, discrete=True),
        Declaration("stop-cheap", goes_on=True, discrete=False, false_stop=CHEAP_FALSE_STOP),
        Declaration("discrete-cheap", goes_on=True, discrete=True, false_stop=CHEAP_FALSE_STOP),
        Declaration(
            "stop-cheap-first",
            goes_on=True,
            discrete=False,
            false_stop=CHEAP_FALSE_STOP,
            weaned=True,
        ),
        Declaration(
            "stop-cheap-rare",
            goes_on=True,
            discrete=False,
            false_stop=CHEAP_FALSE_STOP,
            weaned=True,
            wean_false_stops=WEAN_FALSE_STOPS,
        ),
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


class FalseStopWrapper(gym.Wrapper):
    """A wrapper that sees each new stop declared off its goal (``info["stops"]`` grown and
    ``info["last_stop"]`` not a success), counted from its last reset."""

    def __init__(self, env: gym.Env) -> None:
        gym.Wrapper.__init__(self, env)
        self._stops = 0

    def reset(self, **kwargs):
        """Reset the env and the count of stops seen."""
        self._stops = 0
        return self.env.reset(**kwargs)

    def new_false_stop(self, info: dict) -> bool:
        """Whether the step whose ``info`` this is declared a new false stop."""
        stops = int(info["stops"])
        new = stops > self._stops and not info["last_stop"]["success"]
        self._stops = stops
        return new


class GradedFalseStop(FalseStopWrapper, gym.utils.RecordConstructorArgs):
    """A false stop's cost graded by how far it falls short (training legs of ``stop-graded``,
    over an env whose false stop costs :data:`GOES_ON_FALSE_STOP` and goes on).

    A stop ``d`` metres from its goal (``info["last_stop"]["true_distance_m"]``, judged at
    the true position as the task judges it) costs ``min(progress * d, -GOES_ON_FALSE_STOP)``:
    the progress reward those metres would have paid. Every false stop still costs (``d`` is
    above the goal radius), so none pays better than none; the correct stop pays the goal.
    """

    def __init__(self, env: gym.Env, progress: float) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, progress=progress)
        FalseStopWrapper.__init__(self, env)
        if progress <= 0:
            raise ValueError(f"GradedFalseStop needs reward.progress > 0, got {progress:g}")
        self._progress = progress

    def step(self, action):
        """Step the env; a new false stop's flat cost is given back less its graded cost."""
        observation, reward, terminated, truncated, info = self.env.step(action)
        if self.new_false_stop(info):
            distance = float(info["last_stop"]["true_distance_m"])
            cost = min(self._progress * distance, -GOES_ON_FALSE_STOP)
            reward = float(reward) - GOES_ON_FALSE_STOP - cost  # the flat cost, given back graded
        return observation, reward, terminated, truncated, info


class WeanedFalseStop(FalseStopWrapper, gym.utils.RecordConstructorArgs):
    """The weaned designs' training legs: over an env whose false stop costs ``cheap`` and goes
    on, once the env's last :data:`WEAN_LEGS` legs succeeded at :data:`WEAN_SUCCESS` and
    declared at most ``max_false_stops`` false stops a leg on average (see the module), a false
    stop ends the leg and costs ``task_false_stop`` in all, as it does on a route.
    ``info["weaned"]`` says which rule the step ran under."""

    def __init__(
        self,
        env: gym.Env,
        cheap: float,
        task_false_stop: float,
        max_false_stops: float = math.inf,
    ) -> None:
        gym.utils.RecordConstructorArgs.__init__(
            self, cheap=cheap, task_false_stop=task_false_stop, max_false_stops=max_false_stops
        )
        FalseStopWrapper.__init__(self, env)
        if not task_false_stop <= cheap < 0:
            raise ValueError(
                f"WeanedFalseStop needs task_false_stop <= cheap < 0, got {task_false_stop:g} "
                f"and {cheap:g}"
            )
        if not max_false_stops >= 0:
            raise ValueError(f"WeanedFalseStop needs max_false_stops >= 0, got {max_false_stops}")
        self._extra = task_false_stop - cheap
        self._max_false_stops = max_false_stops
        self._legs: list[tuple[bool, int]] = []  # (success, false stops) of the last legs
        self._leg_false_stops = 0
        self.weaned = False

    def reset(self, **kwargs):
        """Reset the env and the counts of stops seen; ``info["weaned"]`` from the start."""
        self._leg_false_stops = 0
        observation, info = super().reset(**kwargs)
        return observation, {**info, "weaned": self.weaned}

    def step(self, action):
        """Step the env; weaned, a new false stop ends the leg at the task's cost."""
        observation, reward, terminated, truncated, info = self.env.step(action)
        if self.new_false_stop(info):
            self._leg_false_stops += 1
            if self.weaned:
                reward, terminated = float(reward) + self._extra, True
        info = {**info, "weaned": self.weaned}
        if terminated or truncated:
            leg = (bool(info["success"]), self._leg_false_stops)
            self._legs = [*self._legs[-(WEAN_LEGS - 1) :], leg]
            self.weaned = self.weaned or self._ready()
        return observation, reward, terminated, truncated, info

    def _ready(self) -> bool:
        """Whether the last legs meet the weaning rule."""
        if len(self._legs) < WEAN_LEGS:
            return False
        success = np.mean([ok for ok, _ in self._legs])
        false_stops = np.mean([count for _, count in self._legs])
        return bool(success >= WEAN_SUCCESS and false_stops <= self._max_false_stops)
