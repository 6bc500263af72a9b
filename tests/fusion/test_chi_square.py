"""The chi-square quantile of the gates, without SciPy in the env process."""

import subprocess
import sys

import pytest
from scipy.special import gammaincinv

from stsf_gym.fusion.chi_square import chi_square_quantile, chi_square_tail


@pytest.mark.parametrize("dof", [1, 2, 3, 4, 5, 6])
@pytest.mark.parametrize("probability", [0.05, 0.5, 0.9, 0.99, 0.999, 0.9999])
def test_quantile_agrees_with_scipy(dof, probability):
    expected = 2 * gammaincinv(dof / 2, probability)
    assert chi_square_quantile(probability, dof) == pytest.approx(expected, rel=1e-13)
    assert chi_square_tail(chi_square_quantile(probability, dof), dof) == pytest.approx(
        1 - probability, rel=1e-10
    )


@pytest.mark.parametrize(("probability", "dof"), [(0.0, 3), (1.0, 3), (0.5, 0), (0.5, 2.5)])
def test_bad_arguments_are_refused(probability, dof):
    with pytest.raises(ValueError, match=r"probability|degrees of freedom"):
        chi_square_quantile(probability, dof)


@pytest.mark.slow
def test_a_rendered_stsf_env_process_does_not_need_scipy():
    # SciPy made unimportable: numba, which imports it only to check its version and to link
    # its BLAS when present, goes on without it; the env and the estimator must not need it
    code = (
        "import sys; sys.modules['scipy'] = None\n"
        "import gymnasium as gym, stsf_gym\n"
        "from stsf_gym.wrappers import PoseEstimateWrapper\n"
        "env = PoseEstimateWrapper(gym.make('stsf_gym/Corridor-v0', camera__width=64,"
        " camera__height=48), 'stsf')\n"
        "env.reset(seed=0)\n"
        "for _ in range(4): env.step(env.action_space.sample() * 0)\n"
        "print(sorted(m for m, mod in sys.modules.items() if mod and m.split('.')[0] == 'scipy'))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip().splitlines()[-1] == "[]"
