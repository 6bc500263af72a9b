"""The PyBullet corridor world: builder, robot, sensors and the Gymnasium env class."""

from envs.corridor_env import CorridorEnv

__all__ = ["CorridorEnv"]
