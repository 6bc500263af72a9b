"""nees.png: a panel per pose source whose titles never run into one another."""

from itertools import pairwise
from types import SimpleNamespace

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg

from stsf_gym.experiments.plotting.consistency import nees_figure

NAMES = ["odometry", "conventional", "conventional-filter", "stsf", "ekf", "smoother", "mcl"]


def _episode() -> SimpleNamespace:
    times = np.arange(0, 20, 0.1)
    return SimpleNamespace(times=list(times), nees_trace=np.full(len(times), 3.0))


def test_the_panel_titles_do_not_overlap():
    fig = nees_figure({name: [_episode()] for name in NAMES})
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    boxes = [ax.title.get_window_extent(renderer) for ax in fig.axes]
    assert all(left.x1 < right.x0 for left, right in pairwise(boxes))
    assert all("95 % bounds" in ax.get_title() for ax in fig.axes)
