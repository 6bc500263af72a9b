"""Experiments run by the CLI: the demo and the paper's reproductions.

This is the application layer: unlike the core library (fusion, vision, estimators), it may
use the baseline agents in ``agents``.
"""
