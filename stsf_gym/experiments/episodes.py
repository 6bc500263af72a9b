"""One seeded episode of an agent driving on an estimator's pose, and what it measured.

The agent sees the wrapped observation (``obs["pose"]`` is the estimate); the true pose from
``info`` is used only to score the run. A run of many episodes keeps each finished episode
in its own JSON file, so an interrupted run resumes where it stopped.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from stsf_gym.episode_env import make_episode_env
from stsf_gym.estimators import estimator_settings
from stsf_gym.experiments.cache import run_cached
from stsf_gym.wrappers import TRUTH

TRACE_EVERY = 10  # steps between stored trajectory samples
RESULT_VERSION = 4  # bumped when EpisodeResult changes, so older episode files are rerun


@dataclass(frozen=True)
class EpisodeSpec:
    """What to run: world, estimator, agent, seed and env overrides (JSON-friendly)."""

    world: str
    estimator: str
    seed: int
    agent: str = "follower"
    env: dict = field(default_factory=dict)
    options: dict = field(default_factory=dict)  # estimator options (part of the cache key)
    agent_options: dict = field(default_factory=dict)  # e.g. the follower's config overrides

    @property
    def key(self) -> str:
        return f"{self.world}-{self.estimator}-{agent_label(self.agent)}-{self.seed}"


@dataclass
class EpisodeResult:
    spec: dict
    outcome: str  # goal | collision | time
    distance: float  # metres driven (true)
    sim_time: float
    steps: int
    errors: list[float]  # position error per stored sample (m)
    heading_errors: list[float]  # rad, per stored sample
    travelled: list[float]  # distance driven at each sample (m)
    times: list[float]  # simulated time of each sample (s)
    true_xy: list[list[float]]
    estimate_xy: list[list[float]]
    covariances: list[list[float]]  # 2x2 position covariance per sample, flattened
    nees: float  # time average of the 3-dof NEES
    nees_trace: list[float]  # NEES at each stored sample
    frames: int
    camera_frames: int
    frames_in_view: int  # camera frames with a landmark wholly in view (true camera pose)
    frames_matched: int
    landmark_updates: int
    gated_out: int
    relocalised: int
    finite: bool  # pose and covariance finite at every step
    min_cov_eigenvalue: float  # smallest eigenvalue of the covariance over the steps
    stage_ms_per_step: dict[str, float]


def estimator_options(source: str) -> dict:
    """The settings of pose source ``source`` (``configs/estimators/<name>.yaml``) as plain
    values, recorded with every episode (part of its cache key); ``truth`` has none."""
    return {} if source == TRUTH else asdict(estimator_settings(source))


def agent_label(agent: str) -> str:
    """``follower``, or a saved model's file stem and content digest (a file-name part)."""
    if agent == "follower":
        return agent
    from agents.sb3_agent import model_digest

    return f"{Path(agent).stem}-{model_digest(agent)}"


def make_agent(name: str, env, options: dict | None = None):
    """``obs -> action`` for the wrapped ``env``: the follower (``options`` override
    ``configs/agents/follower.yaml``), or a saved SB3 model's path."""
    if name == "follower":
        from agents.follower import PathFollower

        follower = PathFollower.for_env(env, **(options or {}))
        return lambda obs: follower.act(obs["pose"], obs["sonar"])
    if name.endswith(".zip"):
        from agents.sb3_agent import load_agent

        return load_agent(name, env)
    raise ValueError(f"unknown agent {name!r}; known: follower or a saved model (.zip)")


def run_episode(spec: EpisodeSpec) -> EpisodeResult:
    """Drive one episode to its end; score the estimate against the true pose."""
    env = make_episode_env(spec.world, spec.estimator, spec.env, spec.options)
    try:
        act = make_agent(spec.agent, env, spec.agent_options)
        obs, info = env.reset(seed=spec.seed)
        samples: dict[str, list] = {k: [] for k in ("e", "h", "d", "s", "t", "x", "c", "n")}
        nees, steps, frames, in_view, terminated, truncated = [], 0, 0, 0, False, False
        finite, min_eig = True, math.inf
        while not (terminated or truncated):
            obs, _, terminated, truncated, info = env.step(act(obs))
            steps += 1
            if obs["image_new"]:
                frames += 1
                in_view += bool(env.unwrapped.landmarks_in_view())
            error = obs["pose"].astype(float) - info["true_pose"]
            error[2] = math.remainder(error[2], math.tau)
            cov = obs["pose_cov"].reshape(3, 3).astype(float)
            finite = finite and bool(np.isfinite(error).all() and np.isfinite(cov).all())
            if finite:
                min_eig = min(min_eig, float(np.linalg.eigvalsh(cov)[0]))
            nees.append(float(error @ np.linalg.solve(cov, error)))
            if steps % TRACE_EVERY == 0 or terminated or truncated:
                samples["e"].append(float(np.hypot(*error[:2])))
                samples["n"].append(nees[-1])
                samples["h"].append(float(error[2]))
                samples["d"].append(float(info["distance_travelled"]))
                samples["s"].append(float(info["sim_time"]))
                samples["t"].append(info["true_pose"][:2].tolist())
                samples["x"].append(obs["pose"][:2].astype(float).tolist())
                samples["c"].append(cov[:2, :2].ravel().tolist())
        counters = env.estimator.counters
        outcome = "collision" if info["collision"] else "goal" if terminated else "time"
        return EpisodeResult(
            spec=asdict(spec),
            outcome=outcome,
            distance=float(info["distance_travelled"]),
            sim_time=float(info["sim_time"]),
            steps=steps,
            errors=samples["e"],
            heading_errors=samples["h"],
            travelled=samples["d"],
            times=samples["s"],
            true_xy=samples["t"],
            estimate_xy=samples["x"],
            covariances=samples["c"],
            nees=float(np.mean(nees)),
            nees_trace=samples["n"],
            frames=counters.get("frames", 0),
            camera_frames=frames,
            frames_in_view=in_view,
            frames_matched=counters.get("frames_matched", 0),
            landmark_updates=counters.get("landmark_updates", 0),
            gated_out=counters.get("gated_out", 0),
            relocalised=counters.get("relocalised", 0),
            finite=finite,
            min_cov_eigenvalue=min_eig,
            stage_ms_per_step={k: 1000 * v / steps for k, v in env.estimator.timings.items()},
        )
    finally:
        env.close()


def _spec(job: dict) -> EpisodeSpec:
    return EpisodeSpec(**{k: v for k, v in job.items() if k != "version"})


def _run(job: dict) -> EpisodeResult:
    return run_episode(_spec(job))


def _name(job: dict) -> str:
    return _spec(job).key


def run_episodes(
    specs: list[EpisodeSpec], folder: Path, workers: int = 1, desc: str = "episodes"
) -> list[EpisodeResult]:
    """Run ``specs`` (in ``workers`` processes), reusing episodes already in ``folder``."""
    jobs = [{"version": RESULT_VERSION, **asdict(spec)} for spec in specs]
    results = run_cached(_run, jobs, folder, _name, workers, desc)
    return [EpisodeResult(**result) for result in results]
