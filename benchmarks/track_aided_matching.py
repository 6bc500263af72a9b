"""Track-aided matching against the plain detector, by the board's apparent size.

The follower drives the IRL corridor on the true pose (rendered camera, paper profile, the
camera pointed by the wrapper); on every ``--every``-th frame each board in view (true camera
pose) is looked for by the plain detector and by :class:`stsf_gym.vision.predicted.PredictedMatcher`
given the board's true corners shifted by a Gaussian error of ``--error-px`` (a track's
prediction), and once more with the prediction naming another id (which must never match).

    python benchmarks/track_aided_matching.py --seed 0 --error-px 2
"""

from __future__ import annotations

import argparse
from collections import defaultdict

import cv2
import numpy as np
from tqdm import tqdm

from stsf_gym.episode_env import make_episode_env
from stsf_gym.experiments.episodes import make_agent
from stsf_gym.experiments.fig10_11 import PATH_ONLY
from stsf_gym.vision.detector import LandmarkDetector, to_grey
from stsf_gym.vision.landmarks import board_corners
from stsf_gym.vision.predicted import BoardPrediction, PredictedMatcher

BINS = [0, 8, 16, 24, 32, 40, np.inf]  # apparent board size, px


def project(env, world_from_camera: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Pixels of world points through the true camera (K and distortion)."""
    u = env.unwrapped
    camera_from_world = np.linalg.inv(world_from_camera)
    rvec, _ = cv2.Rodrigues(camera_from_world[:3, :3])
    uv, _ = cv2.projectPoints(
        points, rvec, camera_from_world[:3, 3], u.camera_matrix, u.dist_coeffs
    )
    return uv.reshape(-1, 2)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--error-px", type=float, default=2.0, help="prediction error (px)")
    parser.add_argument("--every", type=int, default=2, help="use every n-th camera frame")
    args = parser.parse_args()
    env = make_episode_env("irl_corridor", "truth")
    obs, info = env.reset(seed=args.seed)
    act = make_agent("follower", env, PATH_ONLY)
    pattern = env.unwrapped.config.world.landmark_pattern
    boards = {lm.id: lm.board_corners for lm in env.unwrapped.landmarks}
    detector = LandmarkDetector(pattern, valid_ids=set(boards))
    matcher, rng = PredictedMatcher(pattern), np.random.default_rng(args.seed)
    counts = defaultdict(lambda: np.zeros(3, int))  # boards, plain, aided
    errors, wrong, frame = [], 0, 0
    with tqdm(desc="frames", unit="frame") as progress:
        while True:
            obs, _, terminated, truncated, info = env.step(act(obs))
            if terminated or truncated:
                break
            frame += bool(obs["image_new"])
            if not obs["image_new"] or frame % args.every:
                continue
            progress.update()
            grey, plain = (
                to_grey(obs["image"]),
                {d.landmark_id for d in detector.detect(obs["image"])},
            )
            for landmark_id in env.unwrapped.landmarks_in_view():
                uv = project(env, info["camera_pose"], boards[landmark_id])
                shift = rng.normal(0.0, args.error_px, 2)
                search = 3 * args.error_px + 3
                prediction = BoardPrediction(landmark_id, uv + shift, search)
                match = matcher.match(grey, prediction)
                size_bin = int(np.digitize(prediction.size_px, BINS)) - 1
                counts[size_bin] += [1, landmark_id in plain, match is not None]
                if match is not None:
                    truth = cv2.getPerspectiveTransform(
                        board_corners(pattern).astype(np.float32), uv.astype(np.float32)
                    )
                    true_points = cv2.perspectiveTransform(match.plane_points[:, None], truth)
                    errors.append(np.sqrt(np.mean((true_points[:, 0] - match.image_points) ** 2)))
                other = next(i for i in boards if i != landmark_id)
                wrong += matcher.match(grey, BoardPrediction(other, uv + shift, search)) is not None
    env.close()
    print("| board size (px) | boards | plain detector | track-aided |")
    print("| --- | --- | --- | --- |")
    for b in sorted(counts):
        n, plain_found, aided_found = counts[b]
        print(
            f"| {BINS[b]:g}-{BINS[b + 1]:g} | {n} | {plain_found / n:.2f} | {aided_found / n:.2f} |"
        )
    print(
        f"square-centre error of track-aided matches: median {np.median(errors):.2f} px, "
        f"95 % {np.percentile(errors, 95):.2f} px; matches under another id: {wrong}"
    )


if __name__ == "__main__":
    main()
