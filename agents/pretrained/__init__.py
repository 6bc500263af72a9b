"""Agents shipped trained, with their settings and provenance (as rl-baselines3-zoo ships
its agents): named ``pretrained:<suite>/<algo>-<pose source>`` wherever an agent is named.

``<algo>`` says what ran (:func:`~stsf_gym.agents.model_files.trained_algo`): ``dagger``
(behaviour cloning and DAgger rounds labelled by the follower, no reward), ``dagger+ppo`` (then
PPO on the env's reward) or ``ppo`` (reward only). Names shipped before an agent was renamed
stay valid as **aliases** (``trained-models/aliases.json``, old name -> new): the agents shipped
as ``ppo-*`` were trained with no PPO step (``n_timesteps: 0``), so they are ``dagger-*`` now.

Each lives in ``trained-models/<suite>/<algo>-<pose source>/``: ``seed-S.zip`` per training
seed (the model, its settings inside it), ``seed-S.json`` (its ``train.json``: code digest, config,
machine, validation rounds) and ``agent.json`` (the summary ``stsf-gym agents`` lists, and
what the agent saw when it was shipped: the policy's inputs over the first
:data:`SEEN_STEPS` decisions of a fixed test world, by seed). ``trained-models/manifest.json``
holds the SHA-256 digest of every shipped file; a model is read only when its bytes match it
(:mod:`~stsf_gym.agents.pretrained.shipped_folder`). The package is only read at run time:
:func:`ship` writes to a folder the user names (``--ship-to DIR``), whose agents are named by
their folder (``DIR/<suite>/<algo>-<pose source>``). A change of the code that moves
what an agent sees (its sensors, its observation, its action layout) makes it **stale**
(:func:`stale`): it must be trained again.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np

from stsf_gym.agents.model_files import trained_algo
from stsf_gym.agents.pretrained.shipped_folder import (
    MANIFEST,
    checked_models,
    updated_manifest,
    valid_parts,
)
from stsf_gym.io import write_json
from stsf_gym.results.code_identity import note_data_files
from stsf_gym.validation import ConfigError, did_you_mean

PREFIX = "pretrained:"
MODELS = Path(__file__).parent / "trained-models"  # not a package name: data, not code
ALIASES = MODELS / "aliases.json"  # "<suite>/<old name>" -> "<suite>/<algo>-<pose source>"
SEEN_STEPS = 40  # decisions of the fixed episode whose inputs are kept (20 s at 0.5 s)
SEEN_WORLD_SEED = 0  # the test world of that episode
SEEN_TOLERANCE = 1e-5  # inputs within this of the shipped ones are the same
#: Pose sources whose estimate parts between CPUs from the last bit on: numpy picks its sine,
#: cosine and exp kernels per CPU (AVX-512's on one, libm's on another), and once a last bit
#: differs MCL's resampling keeps other particles (2 cm apart within 5 s, measured between an
#: AMD EPYC and an AVX-512 Xeon). Their agents' inputs are seen on the true pose: what the
#: agent is shown is still checked, the estimator's behaviour has its own version.
CPU_DEPENDENT = frozenset({"mcl"})


def seen_source(pose_source: str) -> str:
    """The pose source an agent trained on ``pose_source`` is seen driving on."""
    return "truth" if pose_source in CPU_DEPENDENT else pose_source


def valid_name(name: str) -> bool:
    """Whether ``name`` has the form ``pretrained:<suite>/<algo>-<pose source>``, each part a
    plain name (:func:`~stsf_gym.agents.pretrained.shipped_folder.valid_parts`: none reaches
    outside :data:`MODELS`); says nothing of whether it is shipped."""
    parts = name.removeprefix(PREFIX).split("/")
    return name.startswith(PREFIX) and len(parts) == 2 and valid_parts(*parts)


def names() -> list[str]:
    """Every shipped agent's name, as ``--agents`` takes it."""
    found = (PREFIX + f"{d.parent.name}/{d.name}" for d in sorted(MODELS.glob("*/*")) if d.is_dir())
    return [name for name in found if valid_name(name)]


def aliases() -> dict[str, str]:
    """Every alias of a shipped agent: old name -> the name it is shipped under now."""
    if not ALIASES.is_file():
        return {}
    renamed = json.loads(ALIASES.read_text())
    return {PREFIX + old: PREFIX + new for old, new in sorted(renamed.items())}


def canonical(name: str) -> str:
    """The name shipped agent ``name`` is shipped under (``name`` itself unless an alias)."""
    return aliases().get(name, name)


def folder(name: str) -> Path:
    """The folder of shipped agent ``name`` (``pretrained:<suite>/<algo>-<pose source>``, or an
    alias of one)."""
    key = canonical(name).removeprefix(PREFIX)
    path = MODELS / key
    if not valid_name(PREFIX + key) or not (path / "agent.json").is_file():
        raise ConfigError(
            f"no shipped agent {name!r}{did_you_mean(name, [*names(), *aliases()])}; shipped: "
            f"{', '.join(names()) or 'none'} "
            "(`stsf-gym agents` lists them)"
        )
    return path


def models(name: str) -> list[Path]:
    """The model file of each training seed of shipped agent ``name``, each checked against
    the manifest (ConfigError for bytes it does not list) and counted as code the run loaded,
    so results quoted from it go stale when it is shipped again."""
    files = checked_models(folder(name))
    note_data_files(files)
    return files


def summary(name: str) -> dict:
    """``agent.json`` of shipped agent ``name``: name, algo, suite, pose source, seeds, val
    success per seed, provenance."""
    return json.loads((folder(name) / "agent.json").read_text())


def listing() -> list[dict]:
    """Every shipped agent's summary, without the inputs it saw, with its ``aliases`` (the old
    names that still name it)."""
    renamed = aliases()
    return [
        {
            **{k: v for k, v in summary(n).items() if k != "seen"},
            "aliases": [old for old, new in renamed.items() if new == n],
        }
        for n in names()
    ]


def shipped_name(model: str | Path) -> str | None:
    """The shipped agent a model file belongs to (None for any other file)."""
    path = Path(model).resolve()
    if path.parent.parent.parent != MODELS.resolve():
        return None
    return PREFIX + f"{path.parent.parent.name}/{path.parent.name}"


def suite_test_env(agent, suite: str, pose_source: str, env: dict | None = None):
    """``agent``'s policy stack over ``suite``'s test worlds on ``pose_source``, with the env
    settings the agent needs (its STOP entry) and ``env`` over the suite's."""
    from stsf_gym.config_files import deep_merge
    from stsf_gym.envs.suite import load_suite
    from stsf_gym.episode_env import make_episode_env

    settings = deep_merge(load_suite(suite).episode_env, agent.env_overrides())
    settings = deep_merge(settings, env or {})
    return agent.wrap(make_episode_env("generated:test", pose_source, settings))


def seen_inputs(
    model: Path, suite: str, pose_source: str, recorded: np.ndarray | None = None
) -> np.ndarray:
    """The policy's inputs over the first :data:`SEEN_STEPS` decisions of ``model`` driving
    test world :data:`SEEN_WORLD_SEED` of ``suite`` on ``pose_source``. With ``recorded``
    (inputs recorded before), each decision is the policy's on the recorded input, not on the
    new one (teacher forcing): the episode follows the recorded one, so a last-bit difference
    of another CPU's floating point (numpy's and the BLAS's kernels are chosen per CPU) is not
    fed back through the policy and grown into another trajectory, while a change of what the
    agent sees shows at the decision it starts."""
    from stsf_gym.agents.trained_agent import SB3Agent

    agent = SB3Agent(str(model))
    env = suite_test_env(agent, suite, pose_source)
    try:
        obs, _ = env.reset(seed=SEEN_WORLD_SEED)
        inputs = []
        for step in range(SEEN_STEPS):
            inputs.append(obs)
            shown = obs if recorded is None or step >= len(recorded) else recorded[step]
            obs, _, terminated, truncated, _ = env.step(agent.act(shown))
            if terminated or truncated:
                break
        return np.array(inputs, dtype=np.float32)
    finally:
        env.close()


def stale() -> list[str]:
    """The shipped agents (and seeds) that the code now shows something else (:func:`moved`)."""
    return [
        f"{name} (seed {seed})"
        for name in names()
        for seed in summary(name)["seeds"]
        if moved(name, seed)
    ]


def moved(name: str, seed: int) -> bool:
    """Whether seed ``seed`` of shipped agent ``name`` now sees other inputs on its fixed
    episode than those recorded when it was shipped."""
    record = summary(name)
    model = folder(name) / f"seed-{seed}.zip"
    then = np.array(record["seen"][str(seed)], dtype=np.float32)
    now = seen_inputs(model, record["suite"], seen_source(record["pose_source"]), then)
    return now.shape != then.shape or not np.allclose(now, then, atol=SEEN_TOLERANCE)


def seen_when_shipped(model: Path, suite: str, pose_source: str) -> np.ndarray:
    """What an agent trained on ``pose_source`` is recorded seeing (:func:`seen_source`)."""
    return seen_inputs(model, suite, seen_source(pose_source))


def ship(training: Path, suite: str, to: Path, replace: bool = False) -> Path:
    """Ship the runs of ``training`` (``stsf-gym train --seeds N`` output: ``seed-S/``
    folders with ``model.zip`` and ``train.json``) as an agent of ``suite`` into the
    shipped-agents folder ``to`` (never the installed package), all checked first and swapped
    in at once (:mod:`~stsf_gym.agents.pretrained.shipping`), and ``to``'s manifest updated
    with its digests; an agent shipped there under the same name is replaced only with
    ``replace``. Returns the agent's folder, ``to/<suite>/<algo>-<pose source>``: the name
    every command takes it by. Its ``agent.json`` names it ``<suite>/<algo>-<pose source>``
    (``pretrained:<suite>/...`` when ``to`` is :data:`MODELS`)."""
    from stsf_gym.agents.pretrained.shipping import (
        build_agent,
        check_destination,
        check_ship_to,
        checked_runs,
        folder_beside,
        swap_in,
    )

    training, to = Path(training), Path(to)
    check_ship_to(to)
    records = checked_runs(training, suite)
    target = to / suite / f"{trained_algo(records[0])}-{records[0]['estimator']}"
    check_destination(target, replace)
    target.parent.mkdir(parents=True, exist_ok=True)
    built = folder_beside(target, "new")
    key = f"{suite}/{target.name}"  # no path of this machine in what is shipped
    name = PREFIX + key if to.resolve() == MODELS.resolve() else key
    try:
        build_agent(name, training, suite, records, built, seen_when_shipped)
        swap_in(built, target)
    finally:
        shutil.rmtree(built, ignore_errors=True)  # gone once swapped in
    write_json(to / MANIFEST, updated_manifest(to, target))
    return target
