"""The first stage of a training run: every setting resolved, typed and checked, before any
file is written or any worker started.

:func:`resolve_run` reads the hyper-parameter file (:func:`load_hyperparams`: observation,
demonstrations and fine-tuning settings typed there, errors naming the key and the layer that
set it), lays the suite's env under the command line's, decides which stages run and records
what will run as ``algo`` (:data:`~stsf_gym.agents.training.hyperparams.METHODS`):

- ``dagger``: cloning and DAgger rounds (the ``demonstrations`` settings), no reward;
- ``dagger+ppo``: the same, then PPO on the env's reward from the clone (``finetune``);
- ``ppo`` / ``sac``: reward alone, for ``n_timesteps``. Asked for by name, ``ppo`` runs what
  the settings enable: with demonstrations it is recorded as ``dagger`` (no reward budget)
  or ``dagger+ppo``, never as what did not run. On a suite, reward alone is the RL-ready
  ids' learner (:mod:`~stsf_gym.agents.rl.ready`): the file's ``rl-ready`` section over
  ``suites``, and training legs declared by :data:`DEFAULT_DECLARATION` (recorded as the
  run's ``declaration``).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

from stsf_gym.agents.rl.declaration import DEFAULT_DECLARATION, Declaration, declaration
from stsf_gym.agents.rl.residual import ResidualConfig
from stsf_gym.agents.training.hyperparams import (
    RESIDUAL,
    Hyperparams,
    check_timesteps,
    learner_of,
    load_hyperparams,
    update_size,
)
from stsf_gym.agents.training.training_envs import env_id_for, evaluation_world
from stsf_gym.config_files import deep_merge, overrides_to_tree
from stsf_gym.envs.generated_env import generated_label
from stsf_gym.envs.suite import load_suite
from stsf_gym.episode_env import resolved_config
from stsf_gym.results.fingerprint import fingerprint
from stsf_gym.results.provenance import provenance
from stsf_gym.validation import ConfigError
from stsf_gym.wrappers import check_pose_source


@dataclass(frozen=True)
class RunSettings:
    """One training run, resolved: what each stage reads."""

    algo: str  # what runs, as recorded (dagger, dagger+ppo, ppo, sac)
    hp: Hyperparams
    world: str
    estimator: str
    suite: str | None
    seed: int
    n_envs: int
    reward_steps: int  # the learning-from-reward stage's budget (0: no such stage)
    env: dict  # the evaluation env's settings
    train_env: dict  # the training envs' (env with train_env over it)
    meta: dict  # what every saved model carries (agents/model_files.py)
    declaration: Declaration | None = None  # plain RL on a suite: how its legs declare

    @property
    def demonstrating(self) -> bool:
        return self.hp.demonstrations.enabled

    @property
    def residual(self) -> ResidualConfig | None:
        """The residual learner's bounds (``--algo residual+ppo``), else None."""
        return self.hp.residual

    @property
    def finetuning(self) -> bool:
        """Learning from reward that starts from a policy that drives already, the clone or
        the residual's follower (the ``finetune`` settings apply)."""
        return (self.demonstrating or self.residual is not None) and self.reward_steps > 0

    def env_spec(self, training: bool) -> dict:
        """The keyword arguments of :func:`make_vec_env` for the training or evaluation envs."""
        return {
            "world": self.world if training else evaluation_world(self.world),
            "estimator": self.estimator,
            "env": self.train_env if training else self.env,
            "observation": self.hp.observation,  # typed: checked once, on load
            "decision_steps": self.meta["decision_steps"],
            "residual": self.meta.get("residual"),
        }


def suite_env(hp: Hyperparams, suite: str, over: dict | None = None) -> dict:
    """The evaluation env of training on ``suite``: the suite's env over the file's, ``over``
    (the command line's) over both; the training legs add ``hp.training.train_env``."""
    return deep_merge(deep_merge(hp.training.env, load_suite(suite).episode_env), over or {})


def recorded_algo(learner: str, demonstrating: bool, reward_steps: int) -> str:
    """``algo`` as what runs: the demonstrations, then reward if it has a budget."""
    if not demonstrating:
        return learner
    return f"dagger+{learner}" if reward_steps else "dagger"


def reward_budget(algo: str, hp: Hyperparams, timesteps: int | None) -> int:
    """The reward stage's budget asked for by ``algo``, the file and ``--timesteps``."""
    asked = timesteps is not None and timesteps > 0
    if algo in ("dagger", "dagger+ppo") and not hp.demonstrations.enabled:
        key = "demonstrations.expert_episodes"
        raise hp.error(f"--algo {algo} needs demonstrations: set {key} above 0", key)
    if algo == "dagger":
        if asked:
            raise ConfigError(f"--algo dagger learns no reward; got --timesteps {timesteps}")
        return 0
    if algo in ("dagger+ppo", RESIDUAL):
        budget = timesteps if timesteps is not None else hp.finetune.timesteps
        if budget < 1:
            key = "finetune.timesteps"
            raise hp.error(f"--algo {algo} needs {key} above 0", key)
        return budget
    return hp.training.n_timesteps if timesteps is None else timesteps


def check_budgets(hp: Hyperparams, n_envs: int, reward_steps: int, finetuning: bool) -> None:
    """Whole updates everywhere: the reward budget and the value warm-up inside it."""
    check_timesteps(hp, n_envs, reward_steps)
    warmup = hp.finetune.value_warmup_steps
    if not finetuning or not warmup:
        return
    size, what = update_size(hp, n_envs)
    if warmup % size or warmup >= reward_steps:
        raise hp.error(
            f"finetune.value_warmup_steps {warmup} must be a multiple of {what} = {size} "
            f"below the reward budget {reward_steps}",
            "finetune.value_warmup_steps",
        )


def resolve_run(
    algo: str,
    estimator: str,
    timesteps: int | None,
    seed: int,
    world: str,
    config: str | Path | None,
    overrides: dict | None,
    n_envs: int | None,
    suite: str | None,
) -> RunSettings:
    """Every setting of a run, checked (ConfigError naming the key and its file otherwise)."""
    check_pose_source(estimator)
    if suite is not None:
        world = generated_label("train")
    env_id = env_id_for(world, estimator, suite)
    hp = load_hyperparams(algo, env_id, config, overrides, suite is not None)
    design = None
    if suite is not None and not hp.demonstrations.enabled and hp.residual is None:
        hp = load_hyperparams(algo, env_id, config, overrides, rl_ready=True)
        design = declaration(DEFAULT_DECLARATION)  # reward alone: as the RL-ready ids learn
    cfg = hp.training
    on_command_line = overrides_to_tree(overrides or {}).get("env", {})
    env = cfg.env if suite is None else suite_env(hp, suite, on_command_line)
    n_envs = cfg.n_envs if n_envs is None else n_envs
    reward_steps = reward_budget(algo, hp, timesteps)
    demonstrating = hp.demonstrations.enabled
    least = 0 if demonstrating else 1  # demonstrations alone are a whole run
    if n_envs < 1 or reward_steps < least:
        raise ConfigError(
            f"--n-envs must be at least 1 and --timesteps at least {least}, "
            f"got {n_envs}, {reward_steps}"
        )
    finetuning = (demonstrating or hp.residual is not None) and reward_steps > 0
    check_budgets(hp, n_envs, reward_steps, finetuning)
    recorded = (
        RESIDUAL if hp.residual else recorded_algo(learner_of(algo), demonstrating, reward_steps)
    )
    training = {k: v for k, v in asdict(cfg).items() if k not in ("env", "observation")}
    training["demonstrations"] = asdict(hp.demonstrations)  # defaults too: they can change
    training["finetune"] = asdict(hp.finetune)
    if hp.residual:
        training["residual"] = asdict(hp.residual)
    hyperparams = {"section": hp.section, **training, **hp.algo_kwargs, "n_envs": n_envs}
    observation = asdict(hp.observation)
    resolved = {
        **resolved_config(world, estimator, env),
        "suite": suite,
        "evaluation_world": evaluation_world(world),
        "algo": recorded,
        "hyperparams": hyperparams,
        "observation": observation,
        **({"declaration": design.name} if design else {}),
    }
    meta = {
        "algo": recorded,
        "seed": seed,
        "suite": suite,
        "evaluation_world": evaluation_world(world),
        "world": world,
        "estimator": estimator,
        "env": env,
        "observation": observation,
        "decision_steps": cfg.decision_steps,
        **({"residual": hp.residual.bounds} if hp.residual else {}),
        "hyperparams": hyperparams,
        "wall_time_s": 0.0,
        "made_by": fingerprint(resolved),
        # the demonstration stage's own: the fine-tuning settings are read after it only, so a
        # change to them alone keeps the demonstrations (the reward stage is trained again)
        "demonstrations_made_by": fingerprint(
            {**resolved, "hyperparams": {k: v for k, v in hyperparams.items() if k != "finetune"}}
        ),
        "provenance": provenance(resolved, [seed]),
    }
    train_env = deep_merge(deep_merge(env, cfg.train_env), design.training_env() if design else {})
    return RunSettings(
        recorded, hp, world, estimator, suite, seed, n_envs, reward_steps, env, train_env, meta,
        design,
    )  # fmt: skip
