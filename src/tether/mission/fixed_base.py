"""``multi_target`` with a base station as a fixed node of the weighted graph.

The continuous-connectivity controller (:class:`~tether.continuous.exploration.strategy.
MultiTargetStrategy`: roles, the prime-traveler election, the consensus, Algorithm 2's
traveling force and the connectivity force of App. A) on a team whose last node is the
base station. The base station is a node of the weighted graph like any robot: its
links weigh in lambda2 and in the connectivity force of its neighbours, and it relays
the election's and the consensus' messages. It never moves: the total force on it is
zero at every sub-step, so its velocity stays zero (a node of infinite mass). It never
has a target, so it is never a traveler, and it is never recruited as a helper.

Whenever the weighted lambda2 of the team with the base station is above
``lambda2_min`` every robot has a (multi-hop) link to the base station; the guard
(``detect`` by default) counts every sub-step where it is not.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tether.continuous.connectivity.dynamics import displacement_step
from tether.continuous.exploration.params import MultiTargetParams
from tether.continuous.exploration.strategy import MultiTargetStrategy
from tether.continuous.exploration.targets import TargetBook

__all__ = ["FixedBaseMultiTarget"]


class FixedBaseMultiTarget(MultiTargetStrategy):
    """``multi_target`` on ``n_robots`` robots followed by one fixed node, the base station.

    Parameters
    ----------
    params
        The controller's parameters (Table 2 preset and the open choices).
    n_robots
        Robots ``0 .. n_robots - 1``; node ``n_robots`` is the base station.
    """

    name = "multi_target_fixed_base"

    def __init__(self, params: MultiTargetParams, n_robots: int) -> None:
        super().__init__(params, TargetBook.empty(n_robots + 1))
        self.base = int(n_robots)

    def forces(self, q: np.ndarray, v: np.ndarray, cache: Any) -> tuple:
        """The team's forces with none on the base station (it stays where it is)."""
        total, f_lambda, _ = super().forces(q, v, cache)
        total = np.array(total, dtype=float)
        total[self.base] = 0.0
        step = displacement_step(v, total, self.integ.mass_kg, self.integ.max_step_m)
        return total, f_lambda, step

    def _recruit(
        self, q: np.ndarray, links: np.ndarray, prime: int, t_s: float, dt_s: float
    ) -> None:
        super()._recruit(q, links, prime, t_s, dt_s)
        self._helpers = self._helpers[self._helpers != self.base]

    def lambda2(self) -> float:
        """The exact weighted lambda2 of the team with the base station, now."""
        return float(self._current[0]) if self._current is not None else float("nan")
