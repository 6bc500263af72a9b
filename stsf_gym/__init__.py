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

- ``stsf_gym/RL-<Level>-<Estimator>-v0``: RL-ready ids, one per suite and pose source: the
  policy's flat ``Box`` input, a decision every 0.5 s, training legs (``split="train"``) or
  full routes (``split="val" | "test"``), ``max_episode_steps`` declared
  (:mod:`stsf_gym.agents.rl.ready`): what SB3 trains from ``gym.make`` alone.
"""

import math

from gymnasium.envs.registration import register, registry

#: The package version, declared here only (``pyproject.toml`` reads it; CHANGELOG.md by version).
__version__ = "0.2.0"

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
    _without_passive_checker()


def _without_passive_checker() -> None:
    """Every stsf-gym id made without Gymnasium's ``PassiveEnvChecker``: a first ``reset``
    refused (a bad ``start_pose``) leaves that checker with no reset data, and the first step
    after a valid reset then fails with its ``TypeError``. The env checks its own actions and
    options; the tests run Gymnasium's and SB3's full ``check_env`` on it."""
    for spec in registry.values():
        if spec.id.startswith("stsf_gym/"):
            spec.disable_env_checker = True


def suite_id(name: str) -> str:
    """``stsf_gym/Suite-<Name>-v0`` of suite ``name``."""
    return f"stsf_gym/Suite-{_title(name)}-v0"


def rl_id(suite: str, estimator: str) -> str:
    """``stsf_gym/RL-<Suite>-<Source>-v0``: the RL-ready id of ``suite`` on ``estimator``."""
    suffix = next(s for s, e in ESTIMATOR_IDS.items() if e == estimator)
    return f"stsf_gym/RL-{_title(suite)}-{suffix}-v0"


def _title(name: str) -> str:
    return name.title().replace("_", "").replace("-", "")


def _register_suites() -> None:
    """The ids of every suite in ``configs/suites/``: the world env and one per pose source."""
    from stsf_gym.config_files import SUITE_DIR, deep_merge, read_yaml

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
        _register_rl(path.stem, env)


def _register_rl(suite: str, env: dict) -> None:
    """The RL-ready ids of ``suite`` (its env settings ``env``), one per pose source, each
    declaring its episodes' most decisions (the suite's time limit over the decision period;
    :func:`stsf_gym.agents.rl.ready.episode_decisions` computes the same from the env, and a
    test holds them equal)."""
    from stsf_gym.config_files import CONFIG_DIR, read_yaml

    defaults = read_yaml(CONFIG_DIR / "default.yaml")["sim"]
    seconds = (env.get("sim") or {}).get("max_episode_seconds", defaults["max_episode_seconds"])
    steps = read_yaml(CONFIG_DIR / "agents" / "ppo.yaml")["suites"]["decision_steps"]
    decisions = math.ceil(seconds / (defaults["control_dt"] * steps) - 1e-9)
    for estimator in ESTIMATOR_IDS.values():
        env_id = rl_id(suite, estimator)
        if env_id not in registry:
            register(
                id=env_id,
                entry_point="stsf_gym.agents.rl.ready:make_rl_env",
                kwargs={"suite": suite, "estimator": estimator},
                max_episode_steps=decisions,
            )


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
