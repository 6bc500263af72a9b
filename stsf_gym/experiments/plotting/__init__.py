"""Figures of the experiments (matplotlib PNG): maps and trajectories, error curves, NEES."""
