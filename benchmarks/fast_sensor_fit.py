"""Fit the fast sensor mode's statistics to the real detector on rendered frames.

Renders the landmark from a grid of distances and viewing angles
(:mod:`stsf_gym.experiments.detector_views`), runs the detector, and fits:

- the detection rate as a logistic function of the board's apparent size in pixels
  (maximum likelihood over every view: ``detect_size_px``, ``detect_size_scale``);
- the feature error: RMS per axis of detected square centres against their true projection
  (``feature_noise_px``);
- false detections: wrong-id detections per frame (``false_detection_rate``);
- track-aided matching: of the views the detector missed, the rate at which STSF's predicted
  matcher finds the board given its corners off by a track's error, as a logistic function of
  the apparent size (maximum likelihood, the same fit: ``aided_size_px``, ``aided_size_scale``).

Then it measures the fast mode with the fitted numbers on fresh views and prints both side by
side. ``--write`` puts the fitted numbers into the camera profile's file,
``configs/cameras/<profile>.yaml`` (its ``fast`` section).

Usage::

    python benchmarks/fast_sensor_fit.py [--profile paper] [--seed 0] [--repeats 3] [--write]
        [--json]
"""

from __future__ import annotations

import argparse
import json
import re
import sys

import gymnasium as gym
import numpy as np
from scipy.optimize import minimize

import stsf_gym  # noqa: F401 - registers the ids
from stsf_gym.envs.config import CONFIG_DIR
from stsf_gym.experiments.detector_views import detection_records, room_world, summarise_records


def fit_detection_rate(sizes: np.ndarray, detected: np.ndarray) -> tuple[float, float]:
    """Maximum-likelihood logistic ``P(detected | size)``: (size at 50 %, width), pixels."""

    def negative_log_likelihood(params: np.ndarray) -> float:
        centre, log_width = params
        z = (sizes - centre) / np.exp(log_width)
        return float(np.sum(np.logaddexp(0.0, np.where(detected, -z, z))))

    start = np.array([np.median(sizes), 0.0])
    result = minimize(negative_log_likelihood, start, method="Nelder-Mead")
    return float(result.x[0]), float(np.exp(result.x[1]))


def fit(records: list[dict]) -> dict:
    sizes = np.array([r["size_px"] for r in records])
    detected = np.array([r["detected"] for r in records])
    centre, width = fit_detection_rate(sizes, detected)
    missed = [r for r in records if r["aided"] is not None]
    aided_centre, aided_width = fit_detection_rate(
        np.array([r["size_px"] for r in missed]), np.array([r["aided"] for r in missed])
    )
    summary = summarise_records(records)
    return {
        "feature_noise_px": round(summary["feature_rms_px"], 4),
        "detect_size_px": round(centre, 3),
        "detect_size_scale": round(width, 3),
        "false_detection_rate": round(summary["wrong_ids_per_view"], 4),
        "aided_size_px": round(aided_centre, 3),
        "aided_size_scale": round(aided_width, 3),
    }


def write_profile_yaml(profile: str, values: dict) -> None:
    """Replace the ``fast`` numbers in the profile's YAML file, keeping its comments."""
    path = CONFIG_DIR / "cameras" / f"{profile}.yaml"
    text = path.read_text()
    for key, value in values.items():
        text, n = re.subn(rf"(\n  {key}: )[^\s#]+", rf"\g<1>{value}", text)
        if n != 1:
            raise RuntimeError(f"fast.{key} not found once in {path}")
    path.write_text(text)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--repeats", type=int, default=3, help="views per distance and angle")
    parser.add_argument("--profile", default="paper", help="camera profile (configs/cameras)")
    parser.add_argument("--write", action="store_true", help="update the profile's YAML file")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    results = {}
    for mode in ("rendered", "fast"):
        camera = {"mode": mode, "profile": args.profile, "fast": results.get("fitted", {})}
        env = gym.make("stsf_gym/Straight10m-v0", world=room_world(), camera=camera)
        try:
            aided_rng = np.random.default_rng(args.seed + 1)  # apart: the views stay the same
            records = detection_records(env, rng, repeats=args.repeats, aided_rng=aided_rng)
        finally:
            env.close()
        if mode == "rendered":
            results["fitted"] = fit(records)
        results[mode] = summarise_records(records)
    if args.write:
        write_profile_yaml(args.profile, results["fitted"])
    if args.json:
        print(json.dumps(results, indent=2))
    else:
        print("fitted camera.fast:", results["fitted"])
        for key in results["rendered"]:
            print(
                f"{key:22s} rendered {results['rendered'][key]!s:24s} fast {results['fast'][key]}"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
