"""``RecordEpisode``: every episode of an env as an MCAP log or a Rerun recording."""

from __future__ import annotations

import math
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

from stsf_gym.estimators import PoseEstimator
from stsf_gym.recording import require_recording
from stsf_gym.recording.records import (
    EpisodeStart,
    FrameDetections,
    Recorder,
    RobotLayout,
    StepRecord,
)
from stsf_gym.validation import ConfigError
from stsf_gym.wrappers import START_STD, sensor_model

#: Recording formats and their file extensions.
FORMATS = {"mcap": ".mcap", "rerun": ".rrd"}


def make_recorder(path: str | Path, fmt: str, frames: str = "raw") -> Recorder:
    """The recorder of ``fmt`` (``mcap`` or ``rerun``) writing ``path``."""
    require_recording(f"--record {fmt}")
    if fmt == "mcap":
        from stsf_gym.recording.mcap_writer import McapRecorder

        return McapRecorder(path, frames)
    if fmt == "rerun":
        from stsf_gym.recording.rerun_writer import RerunRecorder

        return RerunRecorder(path)
    raise ConfigError(f"record format must be one of {sorted(FORMATS)}, got {fmt!r}")


def find_estimator(env: gym.Env) -> PoseEstimator | None:
    """The pose estimator of the first wrapper in ``env``'s stack that runs one."""
    while isinstance(env, gym.Wrapper):
        estimator = getattr(env, "estimator", None)
        if isinstance(estimator, PoseEstimator):
            return estimator
        env = env.env
    return None


def _clocks() -> tuple[float, float]:
    return time.perf_counter(), time.thread_time()


class RecordEpisode(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """Records each episode of a stsf-gym env (any registered id or hand-built stack) to
    ``folder/<name_prefix>.<ext>`` (later episodes ``<name_prefix>-<k>.<ext>``): ``fmt="mcap"``
    (standard ROS 2 messages, replayable by ``stsf-gym replay``; camera frames as ``frames``:
    ``raw`` (default), ``png`` or ``jpeg``) or ``fmt="rerun"`` (a ``.rrd`` for the Rerun viewer).

    Wrap it outermost: it records the observation the env made, the true pose from ``info``
    and the estimate of the :class:`~stsf_gym.wrappers.PoseEstimateWrapper` below it (if
    any). It changes nothing it passes on. A file is complete when its episode ends or the
    env closes. :attr:`paths` lists the files written; :attr:`wall_s` and :attr:`cpu_s` the
    wall and CPU time (this thread's) spent recording: what recording adds to an episode.
    """

    def __init__(
        self,
        env: gym.Env,
        folder: str | Path,
        fmt: str = "mcap",
        frames: str = "raw",
        name_prefix: str = "episode",
        meta: dict | None = None,
    ) -> None:
        gym.utils.RecordConstructorArgs.__init__(
            self, folder=str(folder), fmt=fmt, frames=frames, name_prefix=name_prefix, meta=meta
        )
        gym.Wrapper.__init__(self, env)
        if fmt not in FORMATS:
            raise ConfigError(f"record format must be one of {sorted(FORMATS)}, got {fmt!r}")
        self.folder, self.fmt, self.frames = Path(folder), fmt, frames
        self.name_prefix, self.meta = name_prefix, dict(meta or {})
        self.paths: list[Path] = []
        self.wall_s = self.cpu_s = 0.0
        self._recorder: Recorder | None = None

    def reset(self, *, seed=None, options=None):
        """Finish the previous episode's file, reset the env and start a new recording."""
        self._finish()
        obs, info = self.env.reset(seed=seed, options=options)
        started = _clocks()
        k = len(self.paths)
        stem = self.name_prefix if k == 0 else f"{self.name_prefix}-{k}"
        path = self.folder / f"{stem}{FORMATS[self.fmt]}"
        self._recorder = make_recorder(path, self.fmt, self.frames)
        self.paths.append(path)
        self._recorder.start(self._episode_start(seed, options))
        self._recorder.step(self._record(obs, info, None))
        self._add(started)
        return obs, info

    def step(self, action):
        """Step the env and record the step; the file is finished when the episode ends."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        if self._recorder is not None:
            started = _clocks()
            self._recorder.step(self._record(obs, info, action))
            self._add(started)
            if terminated or truncated:
                collision = bool(info.get("collision", False))
                outcome = "collision" if collision else "goal" if terminated else "time"
                self._finish({"outcome": outcome})
        return obs, reward, terminated, truncated, info

    def close(self):
        """Finish the open recording, then close the env."""
        self._finish()
        return super().close()

    def _finish(self, end: dict | None = None) -> None:
        if self._recorder is not None:
            started = _clocks()
            self._recorder.close(end)
            self._recorder = None
            self._add(started)

    def _add(self, started: tuple[float, float]) -> None:
        wall, cpu = _clocks()
        self.wall_s += wall - started[0]
        self.cpu_s += cpu - started[1]

    def _episode_start(self, seed, options) -> EpisodeStart:
        u = self.env.unwrapped
        cfg = u.config
        estimator = find_estimator(self.env)
        if estimator is not None:
            pose, cov = estimator.mean.copy(), estimator.cov.copy()
        else:
            pose = np.asarray(u.start_pose, float)
            cov = np.diag(np.square(START_STD))
        layout = RobotLayout(
            body_radius=cfg.robot.body_radius,
            sonar_axes=np.asarray(u.sonar.axes, float),
            sonar_height=cfg.sonar.height,
            sonar_fov=math.radians(cfg.sonar.beam_width_deg),
            sonar_limits=(cfg.sonar.min_range, cfg.sonar.max_range),
            wall_height=cfg.world.wall_height,
            max_speed=cfg.robot.max_speed,
            max_yaw_rate=cfg.robot.max_yaw_rate,
        )
        meta = {
            "world": cfg.world.name,
            "path": [list(point) for point in cfg.world.path],
            "seed": seed,
            "camera_mode": cfg.camera.mode if cfg.camera.enabled else "off",
            "pose_source": None if estimator is None else estimator.name,
            "camera_latency": {
                "delay_s": cfg.camera.latency.delay_s,
                "jitter_s": cfg.camera.latency.jitter_s,
            },
            **self.meta,
        }
        return EpisodeStart(sensor_model(self.env), pose, cov, float(u.dt), layout, meta)

    def _record(self, obs: dict, info: dict, action) -> StepRecord:
        estimator = find_estimator(self.env)
        estimates, detections, counters = {}, None, {}
        if estimator is not None:
            estimates[estimator.name] = (estimator.mean.copy(), estimator.cov.copy())
            counters = dict(estimator.counters)
            detector = estimator.detector
            if detector is not None and obs["image_new"] and action is not None:
                detections = FrameDetections(detector.found, detector.aided, detector.predictions)
        return StepRecord(
            time=float(info["sim_time"]),
            obs=obs,
            true_pose=np.asarray(info["true_pose"], float),
            camera_pose=np.asarray(info["camera_pose"], float),
            action=None if action is None else np.asarray(action, float),
            estimates=estimates,
            detections=detections,
            counters=counters,
        )
