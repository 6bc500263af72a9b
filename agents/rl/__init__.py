"""RL-ready envs: the learner's task as ``gym.make`` gives it (:mod:`~stsf_gym.agents.rl.ready`),
and the ways a learner may declare arrival (:mod:`~stsf_gym.agents.rl.declaration`)."""
