"""Baseline agents: the scripted path follower and stable-baselines3 agents."""
