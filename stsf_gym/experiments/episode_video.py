"""Videos of episodes: the agent drives as in the evaluation (same env, seed and agent, so
the same trajectory) while the env's top-down map (``render.view: map``) is recorded, the
whole episode sped up (:data:`SPEED_UP`) so the turns, the drift and the arrival all show.

Each video is a job of the engine (:func:`~stsf_gym.experiments.jobs.engine.run_jobs`):
recorded in worker processes, and skipped when rerun with the same output folder."""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import asdict
from pathlib import Path

import numpy as np

from stsf_gym.agents.registry import make_agent
from stsf_gym.experiments.episodes import EpisodeSpec, make_episode_env
from stsf_gym.experiments.jobs.engine import run_jobs
from stsf_gym.experiments.jobs.spec import JobKind
from stsf_gym.video import VideoWriter
from stsf_gym.yaml_layers import deep_merge

#: Playback speed of the videos relative to simulated time: the IRL corridor's route of about
#: 195 simulated seconds plays in about 20 s.
SPEED_UP = 10.0
#: Frames per second of the videos; a frame every ``SPEED_UP / FPS`` simulated seconds (0.5 s,
#: every fifth 0.1 s step of the follower), and always the episode's last.
FPS = 20.0


def episode_frames(
    spec: EpisodeSpec, seconds: float | None = None, speed_up: float = SPEED_UP
) -> Iterator[tuple[float, np.ndarray]]:
    """``(sim_time, frame)`` of ``spec``'s episode (the agent drives as in the evaluation,
    the env's map view rendered): the start, then a frame each ``speed_up / FPS`` simulated
    seconds, and the last step's, until the episode ends or ``seconds`` of it have run."""
    agent = make_agent(spec.agent, spec.agent_options)
    settings = deep_merge(spec.env, agent.env_overrides())  # as run_episode drives it
    env = make_episode_env(
        spec.world, spec.estimator, {**settings, "render_mode": "rgb_array"}, spec.options
    )
    try:
        driven = agent.wrap(env)
        obs, info = driven.reset(seed=spec.seed)
        agent.begin(driven)
        period, due = speed_up / FPS, 1  # frames fall due at multiples of period: no drift
        yield 0.0, env.render()
        done = False
        while not done:
            obs, _, terminated, truncated, info = driven.step(agent.act(obs))
            now = info["sim_time"]
            done = terminated or truncated or (seconds is not None and now >= seconds - 1e-9)
            if done or now >= due * period - 1e-9:
                due = math.floor(now / period + 1e-9) + 1
                yield now, env.render()
    finally:
        env.close()


def record_episode(
    spec: EpisodeSpec, stem: str | Path, seconds: float | None = None, speed_up: float = SPEED_UP
) -> Path:
    """Record ``spec``'s episode (:func:`episode_frames`), played ``speed_up`` times faster than
    simulated time, as ``stem.mp4`` (``stem.gif`` without an encoder); return the file."""
    with VideoWriter(stem, FPS) as video:
        for _, frame in episode_frames(spec, seconds, speed_up):
            video.append(frame)
    return video.path


def _record(job: dict) -> dict:
    spec = EpisodeSpec(**job["spec"])
    stem = Path(job["folder"]) / spec.estimator
    return {"file": record_episode(spec, stem, job["seconds"], job["speed_up"]).name}


#: Videos as jobs of the engine: keyed and resolved as their episode.
VIDEO_JOBS = JobKind(
    _record,
    lambda job: EpisodeSpec(**job["spec"]).key,
    lambda job: EpisodeSpec(**job["spec"]).resolved(),
)


def record_videos(
    specs: list[EpisodeSpec],
    folder: str | Path,
    seconds: float | None = None,
    workers: int = 1,
    speed_up: float = SPEED_UP,
) -> dict[str, str]:
    """One video per spec in ``folder`` (``<estimator>.mp4``) of its whole episode (or its
    first ``seconds``), in ``workers`` processes; returns estimator -> file name."""
    folder = Path(folder)
    jobs = [
        {"spec": asdict(s), "folder": str(folder), "seconds": seconds, "speed_up": speed_up}
        for s in specs
    ]
    ran = run_jobs(VIDEO_JOBS, jobs, folder / "jobs.sqlite", "videos", workers=workers)
    return {spec.estimator: done["file"] for spec, done in zip(specs, ran.results, strict=True)}
