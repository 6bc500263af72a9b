"""stsf-gym: a PyBullet corridor world and baselines for STSF sensor fusion.

Importing the package registers the environments with Gymnasium (idempotently):

- ``stsf_gym/Corridor-v0``: the IRL corridor (about 24 m with a turn, 8 landmarks).
- ``stsf_gym/Straight10m-v0``: a straight 10 m corridor (the paper's Fig. 10).
- ``stsf_gym/Generated-v0``: a generated corridor world per episode (``split="train"`` or
  ``"test"``, :mod:`stsf_gym.envs.generated_env`).

- ``stsf_gym/Suite-<Level>-v0``: a benchmark suite's generated worlds under the declared-stop
  task with its STOP action entry (:data:`SUITE_TASK`), one per ``configs/suites/<level>.yaml``
  (:mod:`stsf_gym.envs.suite`).

Each also has an id per pose source, e.g. ``stsf_gym/Corridor-STSF-v0`` or
``stsf_gym/Suite-Sparse-EKF-v0`` (see below).
"""

from gymnasium.envs.registration import register, registry

__version__ = "0.1.0"

#: Registered environment ids and the world each one loads from ``configs/worlds``.
ENV_WORLDS: dict[str, str] = {
    "stsf_gym/Corridor-v0": "irl_corridor",
    "stsf_gym/Straight10m-v0": "straight_10m",
}


#: Estimators with an estimating id per world, e.g. ``stsf_gym/Corridor-STSF-v0``: the env of
#: an episode (:func:`stsf_gym.episode_env.make_episode_env`: the env wrapped in
#: :class:`stsf_gym.wrappers.PoseEstimateWrapper` and, over it,
#: :class:`stsf_gym.wrappers.CameraPointingWrapper`, which points the camera).
ESTIMATOR_IDS: dict[str, str] = {
    "Odometry": "odometry",
    "Conventional": "conventional",  # the paper's: the current two frames only
    "ConventionalFilter": "conventional-filter",  # the same pairs, merged recursively
    "STSF": "stsf",
    "EKF": "ekf",
    "Smoother": "smoother",  # the fixed-lag factor-graph smoother (gtsam)
    "MCL": "mcl",  # Monte Carlo localization on the sonar and the boards
    "Truth": "truth",  # privileged: the true pose, for reference runs
}

#: What every suite id adds to its suite file's env: the declared-arrival task's STOP entry
#: (Habitat's STOP), in the registration itself, so no client's keyword arguments (rl-zoo3's
#: ``--env-kwargs``, an evaluation env built from other ones) can leave it out. A client's
#: ``task`` section merges key by key over it; only ``task={"stop_action": False}`` said in
#: so many words removes it.
SUITE_TASK = {"task": {"stop_action": True}}


#: The id of generated worlds (``split="train" | "val" | "test"``,
#: ``reset(options={"world_seed": k})``).
GENERATED_ID = "stsf_gym/Generated-v0"


def register_envs() -> None:
    """Register every stsf-gym id that is not registered yet."""
    if GENERATED_ID not in registry:
        register(id=GENERATED_ID, entry_point="stsf_gym.envs.generated_env:GeneratedCorridorEnv")
    _register_estimating(GENERATED_ID, "generated")
    for env_id, world in ENV_WORLDS.items():
        if env_id not in registry:
            register(
                id=env_id,
                entry_point="stsf_gym.envs.corridor_env:CorridorEnv",
                kwargs={"world": world},
            )
        _register_estimating(env_id, world)
    _register_suites()


def suite_id(name: str) -> str:
    """``stsf_gym/Suite-<Name>-v0`` of suite ``name``."""
    return f"stsf_gym/Suite-{name.title().replace('_', '').replace('-', '')}-v0"


def _register_suites() -> None:
    """The ids of every suite in ``configs/suites/``: the world env and one per pose source."""
    from stsf_gym.yaml_layers import SUITE_DIR, deep_merge, read_yaml

    for path in sorted(SUITE_DIR.glob("*.yaml")):
        suite = read_yaml(path)  # checked when an env is made (stsf_gym.envs.suite)
        generator = suite.get("generator") or {}
        env = deep_merge(suite.get("env") or {}, SUITE_TASK)
        env_id = suite_id(path.stem)
        if env_id not in registry:
            register(
                id=env_id,
                entry_point="stsf_gym.envs.generated_env:make_suite_env",
                kwargs={"env": {"generator": generator, **env}},
            )
        _register_estimating(env_id, "generated", {**env, "generator": generator})


def _register_estimating(env_id: str, world: str, env: dict | None = None) -> None:
    """``<env_id minus -v0>-<Estimator>-v0`` for every estimator: the env of ``world`` (with
    the env settings ``env``, if any) with the pose estimate wrapper."""
    for suffix, estimator in ESTIMATOR_IDS.items():
        estimating_id = env_id.replace("-v0", f"-{suffix}-v0")
        if estimating_id not in registry:
            kwargs = {"world": world, "estimator": estimator}
            register(
                id=estimating_id,
                entry_point="stsf_gym.episode_env:make_episode_env",
                kwargs={**kwargs, "env": env} if env is not None else kwargs,
            )


register_envs()
