"""The PyBullet corridor world: config schema, simulator, world builder, robot, sensors and the
Gymnasium env class (``stsf_gym.envs.corridor_env.CorridorEnv``). Importing ``envs`` alone does not
load PyBullet, so the config schema and sensor models are usable without it."""
