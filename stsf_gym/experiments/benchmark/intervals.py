"""Intervals of the benchmark: success rates, paired differences, bootstrap aggregates.

- :func:`wilson` -- the Wilson score interval of a proportion (Wilson 1927), which keeps its
  coverage near 0 and 1 where the normal (Wald) interval fails (Brown, Cai and DasGupta 2001).
- :func:`newcombe_paired` -- the interval of the difference of two **paired** proportions,
  Newcombe (1998, Stat. Med. 17:873), method 10: Wilson intervals of both margins combined
  with the correlation ``phi`` of the pairs. Two pose sources driven on the same worlds and
  seeds share most of their luck; the pairing removes it, so the interval is narrower than
  that of two independent rates.
- :func:`paired_bootstrap` -- percentile bootstrap of the mean difference of paired values
  (SPL, distance at the stop): pairs resampled together.
- :func:`stratified_bootstrap` -- the aggregate of rliable (Agarwal et al. 2021): a statistic of
  several strata (suites, or training seeds), bootstrapped by resampling runs *within* each
  stratum, percentile interval. rliable itself is not a dependency: it is an sdist that pulls
  in ``arch``, ``pandas`` and ``seaborn`` for these few lines.
- :func:`iqm` -- the interquartile mean (rliable's recommended aggregate over seeds), and
  :func:`seed_iqm`, the IQM over training runs of their mean scores with its interval;
  :func:`paired_seed_iqm`, the difference of two such IQMs paired run by run and world by
  world.

Every draw comes from a seeded ``numpy.random.Generator``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

Z95 = 1.959963984540054  # two-sided 95 % normal quantile
BOOTSTRAP_SAMPLES = 2000


def wilson(successes: int, trials: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval of ``successes / trials``; (0, 1) without trials."""
    if trials == 0:
        return 0.0, 1.0
    p = successes / trials
    denominator = 1 + z * z / trials
    centre = (p + z * z / (2 * trials)) / denominator
    half = z / denominator * math.sqrt(p * (1 - p) / trials + z * z / (4 * trials * trials))
    # the interval holds p even where rounding leaves centre + half a hair below 1 at p = 1
    return min(max(0.0, centre - half), p), max(min(1.0, centre + half), p)


def newcombe_paired(first: Sequence[bool], second: Sequence[bool], z: float = Z95) -> dict:
    """Difference ``rate(first) - rate(second)`` of paired outcomes (pair ``i`` on the same
    world and seed) and its interval, Newcombe (1998) method 10."""
    x, y = np.asarray(first, bool), np.asarray(second, bool)
    if x.shape != y.shape or x.ndim != 1 or not len(x):
        raise ValueError(f"paired outcomes need equal, non-empty lengths, got {x.shape}, {y.shape}")
    n = len(x)
    a, b = int(np.sum(x & y)), int(np.sum(x & ~y))
    c, d = int(np.sum(~x & y)), int(np.sum(~x & ~y))
    p1, p2 = (a + b) / n, (a + c) / n
    l1, u1 = wilson(a + b, n, z)
    l2, u2 = wilson(a + c, n, z)
    margins = (a + b) * (c + d) * (a + c) * (b + d)
    phi = (a * d - b * c) / math.sqrt(margins) if margins > 0 else 0.0
    delta = math.sqrt(max((p1 - l1) ** 2 - 2 * phi * (p1 - l1) * (u2 - p2) + (u2 - p2) ** 2, 0))
    epsilon = math.sqrt(max((u1 - p1) ** 2 - 2 * phi * (u1 - p1) * (p2 - l2) + (p2 - l2) ** 2, 0))
    difference = p1 - p2
    return {
        "difference": difference,
        "low": max(-1.0, difference - delta),
        "high": min(1.0, difference + epsilon),
        "pairs": n,
        "only_first": b,  # pairs the first succeeded in and the second failed
        "only_second": c,
    }


def paired_bootstrap(
    first: Sequence[float], second: Sequence[float], seed: int = 0
) -> dict[str, float]:
    """Mean of ``first - second`` (paired) and its 95 % percentile bootstrap interval."""
    differences = np.asarray(first, float) - np.asarray(second, float)
    rng = np.random.default_rng(seed)
    picks = rng.integers(len(differences), size=(BOOTSTRAP_SAMPLES, len(differences)))
    means = differences[picks].mean(axis=1)
    low, high = np.percentile(means, [2.5, 97.5])
    return {"difference": float(differences.mean()), "low": float(low), "high": float(high)}


def iqm(values: Sequence[float]) -> float:
    """Interquartile mean: the mean of the middle 50 % (scipy's ``trim_mean(x, 0.25)``)."""
    ordered = np.sort(np.asarray(values, float))
    cut = len(ordered) // 4
    return float(np.mean(ordered[cut : len(ordered) - cut]))


def stratified_bootstrap(
    strata: Sequence[Sequence[float]],
    statistic: Callable[[np.ndarray], float] = np.mean,
    seed: int = 0,
) -> dict[str, float]:
    """``statistic`` of the values of all strata together, and its 95 % interval: each
    bootstrap sample resamples every stratum's values within that stratum (rliable's
    ``StratifiedBootstrap``), so each stratum keeps its weight."""
    groups = [np.asarray(values, float) for values in strata]
    rng = np.random.default_rng(seed)
    estimates = [
        statistic(np.concatenate([g[rng.integers(len(g), size=len(g))] for g in groups]))
        for _ in range(BOOTSTRAP_SAMPLES)
    ]
    low, high = np.percentile(estimates, [2.5, 97.5])
    return {
        "estimate": float(statistic(np.concatenate(groups))),
        "low": float(low),
        "high": float(high),
    }


def seed_iqm(scores: Sequence[Sequence[float]], seed: int = 0) -> dict:
    """The interquartile mean over training runs of each run's mean score over the worlds,
    ``scores[run][world]`` (rliable's score matrix, runs x tasks, with the worlds as tasks:
    a run's score on the suite is its mean over the worlds, then runs are aggregated). The
    IQM of the flattened matrix would trim the failures themselves whenever outcomes are 0/1
    and over 75 % succeed. Its 95 % interval resamples the worlds and, within the sample, the
    runs (two-level percentile bootstrap), so it carries both the spread between worlds and
    that between training seeds."""
    matrix = np.asarray(scores, float)
    runs, worlds = matrix.shape
    rng = np.random.default_rng(seed)
    estimates = [
        iqm(matrix[rng.integers(runs, size=runs)][:, rng.integers(worlds, size=worlds)].mean(1))
        for _ in range(BOOTSTRAP_SAMPLES)
    ]
    low, high = np.percentile(estimates, [2.5, 97.5])
    per_run = matrix.mean(axis=1)
    return {
        "estimate": iqm(per_run),
        "low": float(low),
        "high": float(high),
        "per_run": per_run.tolist(),
    }


def paired_seed_iqm(
    first: Sequence[Sequence[float]], second: Sequence[Sequence[float]], seed: int = 0
) -> dict:
    """``IQM(first) - IQM(second)`` of two score matrices ``[run][world]`` paired cell by cell
    (run ``i`` of ``first`` beside run ``i`` of ``second``, on the same worlds), and its 95 %
    interval: each bootstrap sample draws one set of worlds and runs and takes it from both,
    so the pairing removes the luck both sides share (:func:`seed_iqm`'s two levels)."""
    a, b = np.asarray(first, float), np.asarray(second, float)
    if a.shape != b.shape or a.ndim != 2 or not a.size:
        raise ValueError(
            f"paired score matrices need one non-empty shape, got {a.shape}, {b.shape}"
        )
    runs, worlds = a.shape
    rng = np.random.default_rng(seed)
    estimates = []
    for _ in range(BOOTSTRAP_SAMPLES):
        r, w = rng.integers(runs, size=runs), rng.integers(worlds, size=worlds)
        estimates.append(iqm(a[r][:, w].mean(1)) - iqm(b[r][:, w].mean(1)))
    low, high = np.percentile(estimates, [2.5, 97.5])
    return {
        "difference": iqm(a.mean(1)) - iqm(b.mean(1)),
        "low": float(low),
        "high": float(high),
    }
