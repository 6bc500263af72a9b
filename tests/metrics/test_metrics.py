"""ATE, RPE, NEES and the TUM files, checked against evo on the same files."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from stsf_gym.metrics import (
    ate_rmse,
    chi2_bounds,
    distance_to_path,
    fraction_inside,
    nees,
    path_pairs,
    rpe_per_metre,
)
from stsf_gym.tum import read_tum, write_tum

evo = pytest.importorskip("evo", reason="evo is a dev dependency: pip install -e '.[dev]'")


def trajectories(seed: int = 0, steps: int = 1200):
    """A curved true path at 0.12 m/s, 10 Hz, and an estimate with drift and noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(steps) * 0.1
    yaw = 0.3 * np.sin(t / 10.0)
    xy = np.cumsum(0.012 * np.column_stack([np.cos(yaw), np.sin(yaw)]), axis=0)
    truth = np.column_stack([xy, yaw])
    drift = np.cumsum(rng.normal(0, 0.004, (steps, 3)), axis=0)
    return t, truth, truth + drift + rng.normal(0, 0.01, (steps, 3))


def evo_results(truth_file: Path, estimate_file: Path, delta: float):
    from evo.core import metrics, sync
    from evo.tools import file_interface

    ref = file_interface.read_tum_trajectory_file(str(truth_file))
    est = file_interface.read_tum_trajectory_file(str(estimate_file))
    ref, est = sync.associate_trajectories(ref, est)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((ref, est))
    rpe = {}
    for name, relation in (
        ("trans", metrics.PoseRelation.translation_part),
        ("rot", metrics.PoseRelation.rotation_angle_deg),
    ):
        metric = metrics.RPE(
            relation, delta, metrics.Unit.meters, all_pairs=False, pairs_from_reference=True
        )
        metric.process_data((ref, est))
        rpe[name] = metric.get_statistic(metrics.StatisticsType.rmse)
    return ape.get_statistic(metrics.StatisticsType.rmse), rpe


def test_tum_round_trip(tmp_path):
    t, truth, _ = trajectories()
    write_tum(tmp_path / "truth.txt", t, truth)
    times, poses = read_tum(tmp_path / "truth.txt")
    np.testing.assert_allclose(times, t, atol=1e-9)
    np.testing.assert_allclose(poses, truth, atol=1e-8)
    first = (tmp_path / "truth.txt").read_text().splitlines()[1].split()
    assert len(first) == 8 and float(first[3]) == 0.0  # timestamp x y z qx qy qz qw


@pytest.mark.parametrize("delta", [1.0, 2.5])
def test_ate_and_rpe_agree_with_evo(tmp_path, delta):
    t, truth, estimate = trajectories(seed=int(delta * 10))
    write_tum(tmp_path / "truth.txt", t, truth)
    write_tum(tmp_path / "estimate.txt", t, estimate)
    _, truth_read = read_tum(tmp_path / "truth.txt")
    _, est_read = read_tum(tmp_path / "estimate.txt")
    ape, rpe = evo_results(tmp_path / "truth.txt", tmp_path / "estimate.txt", delta)
    ours = rpe_per_metre(truth_read, est_read, delta)
    assert ate_rmse(truth_read[:, :2], est_read[:, :2]) == pytest.approx(ape, rel=1e-9)
    assert ours.pairs >= 3
    assert ours.trans_m_per_m * delta == pytest.approx(rpe["trans"], rel=1e-6)
    assert ours.rot_deg_per_m * delta == pytest.approx(rpe["rot"], rel=1e-6)


def test_evo_command_line_reads_our_files(tmp_path):
    """``evo_ape tum truth.txt estimate.txt`` runs unchanged on the files and prints our ATE."""
    t, truth, estimate = trajectories(seed=3)
    write_tum(tmp_path / "truth.txt", t, truth)
    write_tum(tmp_path / "estimate.txt", t, estimate)
    exe = shutil.which("evo_ape", path=str(Path(sys.executable).parent)) or "evo_ape"
    out = subprocess.run(
        [exe, "tum", "truth.txt", "estimate.txt", "--no_warnings"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    rmse = float(next(line.split()[1] for line in out.splitlines() if "rmse" in line))
    assert rmse == pytest.approx(ate_rmse(truth[:, :2], estimate[:, :2]), abs=1e-5)


def test_rpe_of_a_perfect_estimate_with_an_offset_is_zero():
    _, truth, _ = trajectories()
    shifted = truth + np.array([0.5, -0.2, 0.0])  # a constant shift: every relative motion is exact
    result = rpe_per_metre(truth, shifted, 1.0)
    assert result.trans_m_per_m == pytest.approx(0.0, abs=1e-12)
    assert ate_rmse(truth[:, :2], shifted[:, :2]) == pytest.approx(np.hypot(0.5, 0.2))


def test_rpe_of_a_scale_error_is_the_scale_per_metre():
    _, truth, _ = trajectories()
    scaled = truth.copy()
    scaled[:, :2] *= 1.05  # 5 % too long: 5 cm per metre, no rotation error
    result = rpe_per_metre(truth, scaled, 1.0)
    assert result.trans_m_per_m == pytest.approx(0.05, rel=0.05)
    assert result.rot_deg_per_m == pytest.approx(0.0, abs=1e-9)


def test_path_pairs_and_short_paths():
    xy = np.column_stack([np.arange(11) * 0.5, np.zeros(11)])
    assert path_pairs(xy, 1.0) == [(0, 2), (2, 4), (4, 6), (6, 8), (8, 10)]
    assert rpe_per_metre(np.zeros((5, 3)), np.zeros((5, 3))).pairs == 0
    with pytest.raises(ValueError, match="delta"):
        path_pairs(xy, 0.0)


def test_nees_of_gaussian_errors_is_chi_square():
    rng = np.random.default_rng(1)
    cov = np.array([[0.04, 0.01, 0.0], [0.01, 0.02, 0.0], [0.0, 0.0, 0.001]])
    errors = rng.multivariate_normal(np.zeros(3), cov, 4000)
    values = nees(errors, np.broadcast_to(cov, (4000, 3, 3)))
    assert np.mean(values) == pytest.approx(3.0, rel=0.05)
    assert fraction_inside(values, chi2_bounds(3)) == pytest.approx(0.95, abs=0.02)
    assert fraction_inside(2 * values, chi2_bounds(3)) < 0.85  # overconfident: caught
    lo, hi = chi2_bounds(3, runs=10)
    assert lo < 3 < hi and hi - lo < chi2_bounds(3)[1] - chi2_bounds(3)[0]


def test_distance_to_path():
    path = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0]])
    points = np.array([[1.0, 0.5], [5.0, 2.0], [-1.0, 0.0]])
    np.testing.assert_allclose(distance_to_path(points, path), [0.5, 1.0, 1.0])
