"""One seeded episode of an agent driving on an estimator's pose, and what it measured.

The agent sees the wrapped observation (``obs["pose"]`` is the estimate); the true pose from
``info`` is used only to score the run. Every step is recorded (time, distance, true pose,
estimate and covariance), and the estimator's innovations (NIS). A run of many episodes (jobs of
:data:`EPISODE_JOBS`) keeps each finished episode in its own JSON file, so an interrupted run
resumes where it stopped, and writes each episode's true and estimated trajectories as TUM
files.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import gymnasium as gym
import numpy as np

from stsf_gym.agents.registry import make_agent
from stsf_gym.config_files import deep_merge
from stsf_gym.episode_env import make_episode_env, resolved_config
from stsf_gym.estimators import estimator_settings
from stsf_gym.estimators.references.floor import FloorRecorder, batch_floor
from stsf_gym.experiments.jobs.checks import episode_problem
from stsf_gym.experiments.jobs.engine import run_jobs
from stsf_gym.experiments.jobs.spec import JobKind
from stsf_gym.metrics import distance_to_path, nees, pose_error
from stsf_gym.tum import write_tum
from stsf_gym.wrappers import TruePose, sensor_model


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
        label = agent_label(self.agent, self.agent_options)
        return f"{self.world}-{self.estimator}-{label}-{self.seed}"

    def resolved(self) -> dict:
        """Every value this episode runs with: the env's and pose source's settings
        (:func:`~stsf_gym.episode_env.resolved_config`) and the agent's."""
        config = resolved_config(self.world, self.estimator, self.env, self.options)
        return {**config, "agent": agent_config(self.agent, self.agent_options)}


def full_covariances(upper) -> np.ndarray:
    """3x3 covariances ``(..., 3, 3)`` from their upper triangles ``(..., 6)``, as an
    :class:`EpisodeResult` records them (``xx xy xt yy yt tt``)."""
    upper = np.asarray(upper, dtype=float)
    return upper[..., [0, 1, 2, 1, 3, 4, 2, 4, 5]].reshape(*upper.shape[:-1], 3, 3)


@dataclass
class EpisodeResult:
    """One episode, recorded at every control step (the estimator updates at each), starting
    with the pose the estimator starts from at reset (time 0)."""

    spec: dict
    outcome: str  # goal (every goal reached) | collision | missed (a declared stop off) | time
    distance: float  # metres driven (true)
    sim_time: float
    steps: int
    times: list[float]  # simulated time of each record (s)
    travelled: list[float]  # distance driven at each record (m)
    true_poses: list[list[float]]  # [x, y, yaw] (privileged, from info)
    estimates: list[list[float]]  # [x, y, yaw] the agent saw
    covariances: list[list[float]]  # upper triangle of each 3x3 covariance (xx xy xt yy yt tt)
    nis: list[list[float]]  # [NIS, dof] of every measurement innovation the estimator tested
    path_errors: list[float]  # true distance to the world's path (m), the agent's tracking
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
    #: the declared stops (``task.protocol: declare``; ``env.unwrapped.task.stops``), in order
    stops: list[dict] = field(default_factory=list)
    goals: int = 1  # goals of the route
    route_length: float = 0.0  # m along the path from its start to the last goal (SPL's l)
    #: [x, y, yaw] per record of the episode's floor: the batch smoother over all of its
    #: measurements (:mod:`stsf_gym.estimators.references.floor`); None with the camera off
    floor_estimates: list[list[float]] | None = None

    @property
    def floor_errors(self) -> np.ndarray | None:
        """The floor's position error per record (m), None without a floor."""
        if self.floor_estimates is None:
            return None
        return np.hypot(*pose_error(self.floor_estimates, self.true_poses)[:, :2].T)

    @property
    def pose_errors(self) -> np.ndarray:
        """``estimate - truth`` per record, yaw wrapped, ``(N, 3)``."""
        return pose_error(self.estimates, self.true_poses)

    @property
    def errors(self) -> np.ndarray:
        """Position error per record (m)."""
        return np.hypot(*self.pose_errors[:, :2].T)

    @property
    def heading_errors(self) -> np.ndarray:
        """Heading error per record (rad, signed)."""
        return self.pose_errors[:, 2]

    @property
    def true_xy(self) -> np.ndarray:
        return np.asarray(self.true_poses)[:, :2]

    @property
    def estimate_xy(self) -> np.ndarray:
        return np.asarray(self.estimates)[:, :2]

    @property
    def cov_matrices(self) -> np.ndarray:
        """The 3x3 covariance of each record, ``(N, 3, 3)``."""
        return full_covariances(self.covariances)

    @property
    def nees_trace(self) -> np.ndarray:
        """The 3-dof NEES of each record."""
        return nees(self.pose_errors, self.cov_matrices)

    @property
    def nees(self) -> float:
        """Time average of the NEES."""
        return float(np.mean(self.nees_trace))


#: Whose measurement model (board noise, floors, mount) the floor uses.
FLOOR_SETTINGS = "smoother"


def agent_label(agent: str, options: dict | None = None) -> str:
    """``follower``, or a saved model's file stem and content digest (a file-name part)."""
    return make_agent(agent, options).label()


def agent_config(name: str, options: dict | None = None) -> dict:
    """The resolved settings of agent ``name`` with ``options`` over them."""
    return make_agent(name, options).config()


class EpisodeTrace(gym.Wrapper):
    """Records every control step of the pose-estimating env beneath an agent's policy stack
    (time, distance, true pose, estimate and covariance; camera frames; the floor's data), so a
    policy that decides every few steps is scored on every step all the same."""

    def __init__(self, env: gym.Env, estimating, floor: bool = True) -> None:
        super().__init__(env)
        self.estimating, self.wants_floor = estimating, floor
        self.trace: dict[str, list] = {k: [] for k in ("t", "d", "true", "est", "cov")}
        self.frames = self.in_view = self.steps = 0
        self.finite, self.min_eig = True, math.inf
        self.floor, self.info = None, {}

    def reset(self, *, seed=None, options=None):
        """Reset and record the start (the floor's too, with the camera on)."""
        obs, info = self.env.reset(seed=seed, options=options)
        estimating = self.estimating.get_wrapper_attr
        camera = "image_new" in obs and not isinstance(estimating("estimator"), TruePose)
        if self.wants_floor and camera:
            # the floor needs the camera; the true pose needs no floor
            self.floor = FloorRecorder(estimator_settings(FLOOR_SETTINGS))
            self.floor.reset(sensor_model(self.env), estimating("start"), estimating("start_cov"))
        self._record(obs, info)
        return obs, info

    def step(self, action):
        """Step and record the control step."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        self.steps += 1
        if self.floor is not None:
            self.floor.update(obs)
        if obs["image_new"]:
            self.frames += 1
            self.in_view += bool(self.env.unwrapped.landmarks_in_view())
        self._record(obs, info)
        return obs, reward, terminated, truncated, info

    def _record(self, obs: dict, info: dict) -> None:
        cov = obs["pose_cov"].reshape(3, 3).astype(float)
        pose = obs["pose"].astype(float)
        self.finite = self.finite and bool(np.isfinite(pose).all() and np.isfinite(cov).all())
        if self.finite:
            self.min_eig = min(self.min_eig, float(np.linalg.eigvalsh(cov)[0]))
        self.trace["t"].append(float(info["sim_time"]) if self.steps else 0.0)
        self.trace["d"].append(float(info["distance_travelled"]) if self.steps else 0.0)
        self.trace["true"].append(np.asarray(info["true_pose"], dtype=float).tolist())
        self.trace["est"].append(pose.tolist())
        self.trace["cov"].append(cov[np.triu_indices(3)].tolist())
        self.info = info


def run_episode(spec: EpisodeSpec, record: dict | None = None, floor: bool = True) -> EpisodeResult:
    """Drive one episode to its end; record the estimate and the true pose at every step, and
    the floor's measurements (``floor`` False: no floor, a third of an episode's time saved).
    With ``record`` (``{"format": "mcap" | "rerun", "frames": ..., "folder": ...}``) the
    episode is also written as ``folder/<episode>.mcap`` (or ``.rrd``,
    :class:`~stsf_gym.recording.wrapper.RecordEpisode`); it runs the same either way."""
    agent = make_agent(spec.agent, spec.agent_options)
    settings = deep_merge(
        spec.env, agent.env_overrides()
    )  # e.g. the STOP entry it was trained with
    env = estimating = make_episode_env(spec.world, spec.estimator, settings, spec.options)
    if record:
        from stsf_gym.recording.wrapper import RecordEpisode

        env = RecordEpisode(
            env,
            record["folder"],
            record["format"],
            record.get("frames", "raw"),
            spec.key.replace(":", "_"),  # generated:test-... as a portable file name
            meta={"spec": asdict(spec)},
        )
    try:
        traced = EpisodeTrace(env, estimating, floor)
        driven = agent.wrap(traced)
        obs, _ = driven.reset(seed=spec.seed)  # a generated world is drawn here
        agent.begin(driven)
        terminated = truncated = False
        while not (terminated or truncated):
            obs, _, terminated, truncated, _ = driven.step(agent.act(obs))
        info, trace, steps = traced.info, traced.trace, traced.steps
        path = np.asarray(env.unwrapped.config.world.path, dtype=float)
        estimator = estimating.get_wrapper_attr("estimator")
        counters = estimator.counters
        outcome = "collision" if info["collision"] else "time"
        if terminated and not info["collision"]:
            outcome = "goal" if info["success"] else "missed"
        task = env.unwrapped.task
        return EpisodeResult(
            spec=asdict(spec),
            outcome=outcome,
            distance=float(info["distance_travelled"]),
            sim_time=float(info["sim_time"]),
            steps=steps,
            times=trace["t"],
            travelled=trace["d"],
            true_poses=trace["true"],
            estimates=trace["est"],
            covariances=trace["cov"],
            nis=[list(value) for value in estimator.innovations()],
            path_errors=distance_to_path(np.array(trace["true"])[:, :2], path).tolist(),
            frames=counters.get("frames", 0),
            camera_frames=traced.frames,
            frames_in_view=traced.in_view,
            frames_matched=counters.get("frames_matched", 0),
            landmark_updates=counters.get("landmark_updates", 0),
            gated_out=counters.get("gated_out", 0),
            relocalised=counters.get("relocalised", 0),
            finite=traced.finite,
            min_cov_eigenvalue=traced.min_eig,
            stage_ms_per_step={k: 1000 * v / steps for k, v in estimator.timings.items()},
            stops=[{**asdict(stop), "position": list(stop.position)} for stop in task.stops],
            goals=len(task.goals),
            route_length=task.path.project(task.goals[-1]),
            floor_estimates=(
                None if traced.floor is None else batch_floor(traced.floor.data)[0].tolist()
            ),
        )
    finally:
        env.close()


def write_trajectories(episode: EpisodeResult, folder: Path) -> Path:
    """``truth.txt`` and ``estimate.txt`` (TUM format) of the episode in ``folder/<key>/``;
    ``evo_ape tum truth.txt estimate.txt`` reads them unchanged."""
    target = folder / _spec(episode.spec).key
    write_tum(target / "truth.txt", episode.times, episode.true_poses)
    write_tum(target / "estimate.txt", episode.times, episode.estimates)
    return target


#: A job's keys beside its spec's: how to ``record`` the episode, and ``floor`` False (only
#: then in the job) for an episode without the floor.
JOB_EXTRAS = ("record", "floor")


def _spec(job: dict) -> EpisodeSpec:
    return EpisodeSpec(**{k: v for k, v in job.items() if k not in ("version", *JOB_EXTRAS)})


def run_job(job: dict) -> EpisodeResult:
    """The episode of a job (:func:`run_jobs`'s worker): the spec's fields, the result's
    version and, optionally, :data:`JOB_EXTRAS`."""
    return run_episode(_spec(job), **{k: job[k] for k in JOB_EXTRAS if k in job})


#: Episodes as jobs of the engine: keyed by the spec's key, resolved by the spec.
EPISODE_JOBS = JobKind(
    run_job, lambda job: _spec(job).key, lambda job: _spec(job).resolved(), episode_problem
)


def specs_config(specs: list[EpisodeSpec]) -> dict:
    """The resolved configurations of ``specs`` by world, pose source and agent (what a results
    file's provenance records: every value, once per distinct combination)."""
    resolved: dict[str, dict] = {}
    for spec in specs:
        key = f"{spec.world} / {spec.estimator} / {agent_label(spec.agent, spec.agent_options)}"
        if key not in resolved:
            resolved[key] = spec.resolved()
    return resolved


def run_episodes(
    specs: list[EpisodeSpec],
    folder: Path,
    workers: int = 1,
    desc: str = "episodes",
    record: dict | None = None,
    backend: str = "local",
    address: str | None = None,
    floor: bool = True,
) -> list[EpisodeResult]:
    """Run ``specs`` (in ``workers`` processes, or on Ray: :func:`run_jobs`), reusing episodes
    already in ``folder``; the TUM trajectories of each go to
    ``folder/trajectories/<episode>/``. With ``record`` (see :func:`run_episode`) each episode
    is recorded too: a saved episode without that recording is run again; ``floor`` False:
    without the floor (:func:`run_episode`)."""
    extra = {"record": record} if record else {}
    extra |= {} if floor else {"floor": False}
    jobs = [{**asdict(spec), **extra} for spec in specs]
    ran = run_jobs(
        EPISODE_JOBS,
        jobs,
        Path(folder) / "episodes.sqlite",
        desc,
        backend,
        workers,
        address,
        unit="episode",
    )
    results = [EpisodeResult(**r) for r in ran.results]
    for episode in results:
        write_trajectories(episode, Path(folder) / "trajectories")
    return results
