"""Learning from the scripted follower's demonstrations: an expert that labels every state,
behaviour cloning into an SB3 policy, and DAgger rounds (Ross et al. 2011) before RL."""
