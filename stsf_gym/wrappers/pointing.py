"""``CameraPointingWrapper``: points the pan camera, at a landmark from the pose estimate
(:class:`~stsf_gym.estimators.camera_pointing.LandmarkPointer`), or in a sweep while an
unknown start is searched for; the agent's action has no pan entry."""

from __future__ import annotations

import math

import gymnasium as gym

from stsf_gym.estimators.camera_pointing import LandmarkPointer
from stsf_gym.validation import ConfigError, reset_options
from stsf_gym.wrappers.sensor_model import robot_map

#: With an unknown start the pan camera sweeps (a sine of this period, s) until the estimate's
#: position standard deviation first falls below ``FOUND_STD`` (m) with a map board confirming
#: it (the estimator's ``confirmed``, where it has one): pointed from a pose that is not known
#: yet, it would look at walls, and the sonar alone can settle on the wrong end of a corridor.
SWEEP_PERIOD_S, FOUND_STD = 4.0, 0.2


class CameraPointingWrapper(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """Points the pan camera (``camera.control: pan``) of the env from the estimate of the
    :class:`~stsf_gym.wrappers.estimate.PoseEstimateWrapper` beneath it, and takes the pan entry
    out of the agent's action (``action_layout``: ``[v, w]``, or ``[v, w, stop]``).

    Before each step the camera is turned to the landmark of the map that
    :class:`~stsf_gym.estimators.camera_pointing.LandmarkPointer` picks from the estimate's mean.
    After ``reset(options={"unknown_start": True})`` (which the estimate wrapper passes on to
    an estimator that localizes globally, ``mcl``) the wrapper is :attr:`searching`: the camera
    sweeps until the estimate is narrow (:data:`FOUND_STD`) and confirmed by a board; the check
    is made before each step, from the estimate the agent last saw.

    The env's map view rings the landmark the camera is kept on (it asks at each frame).

    Args:
        env: a stsf-gym env with a pan camera, wrapped in a ``PoseEstimateWrapper``.
    """

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.Wrapper.__init__(self, env)
        corridor = env.unwrapped
        if corridor.config.camera.control != "pan":
            raise ConfigError(
                "CameraPointingWrapper points a pan camera; this env's camera.control is "
                f"{corridor.config.camera.control!r}, not 'pan'",
                "camera.control",
            )
        if not env.has_wrapper_attr("estimator"):
            raise ValueError(
                "CameraPointingWrapper points the camera from a pose estimate: it needs a "
                "PoseEstimateWrapper under it, e.g. CameraPointingWrapper(PoseEstimateWrapper("
                "env, 'stsf'))"
            )
        robot = corridor.config.robot
        self.pointer = LandmarkPointer(
            {}, [], robot.camera_forward, math.radians(robot.pan_limit_deg)
        )
        #: the agent's action entries (:class:`~stsf_gym.envs.action_layout.ActionLayout`)
        self.action_layout = env.get_wrapper_attr("action_layout").without("pan")
        self.action_space = self.action_layout.space
        self.searching_since: float | None = None  # set by reset
        corridor.draw_on_map(self._map_marks)

    def reset(self, *, seed=None, options=None):
        """Reset the env (``options`` passed on) and the pointing; ``unknown_start`` starts a
        search."""
        unknown_start = bool(reset_options(options).get("unknown_start", False))
        self.pointer.reset()
        self.searching_since = None
        obs, info = self.env.reset(seed=seed, options=options)
        self.pointer.landmarks, self.pointer.walls = robot_map(self.env)
        if unknown_start:
            self.searching_since = 0.0
        return obs, info

    @property
    def searching(self) -> bool:
        """An unknown start not localized yet (the pan camera sweeps): an agent should not
        trust the pose (:meth:`~stsf_gym.agents.follower.PathFollower.explore`)."""
        return self.searching_since is not None

    def step(self, action):
        """Point the camera from the estimate (or sweep it while searching), then step."""
        estimator = self.env.get_wrapper_attr("estimator")
        if self.searching_since is not None:
            cov = estimator.cov
            narrow = math.sqrt(max(cov[0, 0], cov[1, 1])) < FOUND_STD
            if narrow and estimator.confirmed:
                self.searching_since = None
            else:
                self.searching_since += self.env.unwrapped.dt
        if self.searching_since is not None:
            pan = math.sin(math.tau * self.searching_since / SWEEP_PERIOD_S)
        else:
            pan = self.pointer.pan(estimator.mean) / self.pointer.pan_limit
        layout = self.env.get_wrapper_attr("action_layout")
        return self.env.step(layout.fill(action, self.action_layout, pan=pan))

    def _map_marks(self) -> tuple[dict, tuple[int, ...]]:
        """What the env's map view draws of this wrapper (it asks at each frame): the ring on
        the landmark the camera is kept on."""
        target = self.pointer.target
        return {}, () if target is None else (target,)
