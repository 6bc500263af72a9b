"""The README's animation: the map view of an episode, with the pose estimates and their ellipses.

The follower drives the IRL corridor on STSF (``stsf_gym/Corridor-STSF-v0``); dead reckoning runs
beside it on the same encoder ticks, so the map shows both estimates with their 2-sigma
ellipses over the true pose (black), the camera's field of view, the sonar cones and an inset
of the camera frame. One frame every ``--every`` seconds of simulated time is kept, quantized
to one shared palette, and written as an animated GIF (WebP with a ``.webp`` suffix):

    python examples/animate_episode.py      # docs/figures/episode.gif: the whole episode, 1.7 MB
    python examples/animate_episode.py --seconds 10 --camera fast --out /tmp/short.gif
"""

from __future__ import annotations

import argparse
from pathlib import Path

import gymnasium as gym
import numpy as np
from PIL import Image

import stsf_gym  # noqa: F401  (registers the ids)
from stsf_gym.agents.follower import PathFollower
from stsf_gym.estimators import make_estimator
from stsf_gym.wrappers import START_STD, sensor_model


def frames(seconds: float, every: float, camera: str, seed: int) -> list[np.ndarray]:
    """Map-view frames of the first ``seconds`` of the episode, one per ``every`` seconds."""
    env = gym.make("stsf_gym/Corridor-STSF-v0", render_mode="rgb_array", camera__mode=camera)
    try:
        follower = PathFollower.for_env(env)
        obs, _ = env.reset(seed=seed)
        dt = env.unwrapped.dt
        odometry = make_estimator("odometry")
        odometry.reset(sensor_model(env), obs["pose"], np.diag(np.square(START_STD)))
        drawn: dict = {}  # the map asks for it at each frame it draws
        env.unwrapped.draw_on_map(lambda: (drawn, ()))
        shown, step_every = [], max(1, round(every / dt))
        for step in range(round(seconds / dt) + 1):
            if step:
                obs, _, terminated, truncated, _ = env.step(follower.act(obs["pose"], obs["sonar"]))
                drawn["odometry"] = odometry.update(obs, dt)
                if terminated or truncated:
                    break
            if step % step_every == 0:
                shown.append(env.render())
        return shown
    finally:
        env.close()


def write_animation(images: list[np.ndarray], path: Path, fps: float, colours: int = 48) -> Path:
    """Write ``images`` as an animation at ``fps``, quantized to one palette of ``colours``."""
    palette = Image.fromarray(np.concatenate(images[:: max(1, len(images) // 8)], axis=0))
    palette = palette.quantize(colors=colours)
    pictures = [Image.fromarray(image).quantize(palette=palette) for image in images]
    path.parent.mkdir(parents=True, exist_ok=True)
    pictures[0].save(
        path,
        save_all=True,
        append_images=pictures[1:],
        duration=round(1000 / fps),
        loop=0,
        optimize=True,
    )
    return path


def main(argv: list[str] | None = None) -> Path:
    """Record the episode and write the animation; return its path."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=240.0, help="simulated time shown")
    parser.add_argument("--every", type=float, default=1.5, help="simulated s between frames")
    parser.add_argument("--fps", type=float, default=12.0, help="frames per second played")
    parser.add_argument("--camera", choices=["fast", "rendered"], default="rendered")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("docs/figures/episode.gif"))
    args = parser.parse_args(argv)
    images = frames(args.seconds, args.every, args.camera, args.seed)
    path = write_animation(images, args.out, args.fps)
    print(f"{path}: {len(images)} frames, {path.stat().st_size / 1e6:.2f} MB")
    return path


if __name__ == "__main__":
    main()
