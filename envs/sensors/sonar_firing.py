"""The sonar ring's firing sequence: which transducers fire when (``sonar.firing_order``).

Real rings fire their transducers one after another, not together, so that one's echo is not
taken for another's (a 16-transducer ring at 30 ms per firing needs about half a second per
cycle). With an order, transducer ``order[j]`` fires at ``(n len(order) + j + 1)`` firing
intervals into the episode, cycle after cycle; each reading keeps its own time. Without one,
every transducer fires at each step end.
"""

from __future__ import annotations

from stsf_gym.envs.config import SonarConfig

TIME_EPS = 1e-9


class FiringSchedule:
    """The transducers due to fire as simulated time advances."""

    def __init__(self, cfg: SonarConfig) -> None:
        self.order, self.interval = cfg.firing_order, cfg.firing_interval_s
        self._fired = 0  # firings so far this episode

    @property
    def sequential(self) -> bool:
        return bool(self.order)

    def reset(self) -> None:
        """Start an episode: no transducer fired yet."""
        self._fired = 0

    def due(self, time: float) -> list[tuple[int, float]]:
        """``(transducer, firing time)`` of every firing up to ``time`` not yet returned."""
        fired = []
        while self.sequential and (self._fired + 1) * self.interval <= time + TIME_EPS:
            fired.append(
                (self.order[self._fired % len(self.order)], (self._fired + 1) * self.interval)
            )
            self._fired += 1
        return fired
