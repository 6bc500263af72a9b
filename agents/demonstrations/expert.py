"""The expert of the demonstrations: the path follower on the TRUE pose (or on the student's own
estimate, ``teacher_pose: estimate``), labelling states.

:class:`ExpertLabel` sits directly over the pose-estimating env, beneath the policy's stack,
and writes the follower's action for the state just reached into ``info["expert_action"]``
at every reset and step, whoever drives. The follower is privileged (it sees the true pose from
``info``, as a teacher may: Chen et al. 2019, "Learning by cheating") and heads for the task's
current goal (the observation's ``goal_arc``, while ``goals_left``), wherever the driver's
own stops left it, so it labels any state the learner reaches: DAgger's requirement.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import gymnasium as gym
import numpy as np

from stsf_gym.agents.follower import PathFollower

if TYPE_CHECKING:
    from stsf_gym.agents.observation import PolicyObservation


class ExpertLabel(gym.Wrapper):
    """Adds ``info["expert_action"]``: the follower's action (the env's action layout, its
    ``stop`` entry included) for the true pose and the sonar of the current observation.

    With ``features`` (a :class:`~stsf_gym.agents.observation.PolicyObservation` over the same
    env, told each reset's path, whose ``observation`` makes the policy's of a raw one) it also
    keeps every control step's ``(features, label)``, between the policy's decisions
    too: a state the robot passes while an action is held is a state like any other, and
    labelling it gives the cloning ``decision_steps`` times the data for the same driving.
    :meth:`pop_samples` hands them over. With ``pose="estimate"`` the follower drives on the
    observation's ``pose``, the estimate the student sees, instead of the truth: its labels are
    then a function of the student's information, with nothing it cannot predict.
    """

    def __init__(
        self,
        env: gym.Env,
        features: PolicyObservation | None = None,
        pose: str = "truth",
    ) -> None:
        super().__init__(env)
        if pose not in ("truth", "estimate"):
            raise ValueError(f"the teacher's pose is 'truth' or 'estimate', got {pose!r}")
        self.expert: PathFollower | None = None
        self.features, self.pose = features, pose
        self._samples: list[tuple[np.ndarray, np.ndarray]] = []

    def pop_samples(self) -> tuple[np.ndarray, np.ndarray]:
        """The ``(features, labels)`` of the control steps since the last call, as arrays."""
        samples, self._samples = self._samples, []
        if not samples:
            return np.zeros((0, 0), np.float32), np.zeros((0, 0), np.float32)
        features, labels = zip(*samples, strict=True)
        return np.array(features), np.array(labels)

    def reset(self, *, seed=None, options=None):
        """Reset, and label the first state with a follower of the episode's goals."""
        obs, info = self.env.reset(seed=seed, options=options)
        self.expert = PathFollower.for_env(self.env)  # its goal: the observation's (head_for)
        if self.features is not None:
            self.features.follow_path(info)
        return obs, self._label(obs, info)

    def step(self, action):
        """Step whatever drives, and label the state reached."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, reward, terminated, truncated, self._label(obs, info)

    def _label(self, obs: dict, info: dict) -> dict:
        self.expert.head_for(float(obs["goal_arc"][0]) if obs["goals_left"][0] else None)
        pose = info["true_pose"] if self.pose == "truth" else obs["pose"]
        info["expert_action"] = self.expert.act(pose, obs["sonar"])
        if self.features is not None:
            self._samples.append((self.features.observation(obs), info["expert_action"]))
        return info
