"""A vector env's worker process renders with llvmpipe on one thread unless the user chose."""

import multiprocessing
import os

import pytest

from stsf_gym.envs.rendering.gl_renderer import WORKER_RASTER_THREADS, gl_context


def _threads_in_worker(user_value: str | None) -> str | None:
    """LP_NUM_THREADS in a spawned worker after it made its GL context."""
    if user_value is None:
        os.environ.pop("LP_NUM_THREADS", None)
    else:
        os.environ["LP_NUM_THREADS"] = user_value
    gl_context()
    return os.environ.get("LP_NUM_THREADS")


@pytest.mark.parametrize(
    ("user_value", "expected"), [(None, str(WORKER_RASTER_THREADS)), ("2", "2")]
)
def test_a_worker_renders_on_one_thread_unless_the_user_chose(user_value, expected):
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        assert pool.apply(_threads_in_worker, (user_value,)) == expected
