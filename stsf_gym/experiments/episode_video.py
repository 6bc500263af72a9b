"""Videos of episodes: the agent drives as in the evaluation (same env, seed and agent, so
the same trajectory) while the env's top-down map (``render.view: map``) is recorded.

Each video is a job of :func:`~stsf_gym.experiments.cache.run_cached`: recorded in worker
processes, and skipped when rerun with the same output folder."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

from stsf_gym.agents.registry import make_agent
from stsf_gym.experiments.cache import run_cached
from stsf_gym.experiments.episodes import EpisodeSpec, make_episode_env
from stsf_gym.video import VideoWriter

#: Playback speed of the videos relative to simulated time.
SPEED_UP = 2.0


def record_episode(spec: EpisodeSpec, stem: str | Path, seconds: float) -> Path:
    """Record the first ``seconds`` of simulated time of ``spec``'s episode (or all of it, if
    shorter) as ``stem.mp4`` (``stem.gif`` without an encoder); return the file."""
    env = make_episode_env(
        spec.world, spec.estimator, {**spec.env, "render_mode": "rgb_array"}, spec.options
    )
    try:
        agent = make_agent(spec.agent, spec.agent_options)
        driven = agent.wrap(env)  # a frame per decision of the agent
        dt = env.unwrapped.dt
        with VideoWriter(stem, SPEED_UP / dt) as video:
            obs, info = driven.reset(seed=spec.seed)
            agent.begin(driven)
            video.append(env.render())
            while info.get("sim_time", 0.0) < seconds - 1e-9:
                obs, _, terminated, truncated, info = driven.step(agent.act(obs))
                video.append(env.render())
                if terminated or truncated:
                    break
        return video.path
    finally:
        env.close()


def _record(job: dict) -> dict:
    spec = EpisodeSpec(**job["spec"])
    return {"file": record_episode(spec, Path(job["folder"]) / spec.estimator, job["seconds"]).name}


def record_videos(
    specs: list[EpisodeSpec], folder: str | Path, seconds: float, workers: int = 1
) -> dict[str, str]:
    """One video per spec in ``folder`` (``<estimator>.mp4``), in ``workers`` processes;
    returns estimator -> file name."""
    folder = Path(folder)
    jobs = [{"spec": asdict(s), "folder": str(folder), "seconds": seconds} for s in specs]
    results = run_cached(
        _record,
        jobs,
        folder / "jobs",
        lambda job: EpisodeSpec(**job["spec"]).key,
        workers,
        "videos",
        config=lambda job: EpisodeSpec(**job["spec"]).resolved(),
    )
    return {spec.estimator: result["file"] for spec, result in zip(specs, results, strict=True)}
