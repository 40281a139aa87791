"""Theta as an action: each agent chooses its personality score every step.

The pair condition of the paper (Thm. 1) needs only ``omega_ij + omega_ji = 1``, whatever the
scores, so an agent may change its theta at every step without touching the guarantee. With
``theta_action=True`` an agent's action has one more component ``a`` in [-1, 1] (values outside
are clipped to it, as an action's norm is clipped to 1), mapped on a log scale onto
``[theta_min, theta_max]``::

    theta = theta_min * (theta_max / theta_min) ** ((a + 1) / 2)

so ``a = -1`` is the most egoistic score, ``a = 1`` the most altruistic and ``a = 0`` their
geometric mean. The weights of the step come from both agents' scores of that step
(``rsvo_env.sim.weights``), and the observations that follow carry every neighbour's current score.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rsvo_env.util.validation import check_flag, check_theta_interval

# the range when none is given: the personalities the paper's examples use, both ways
DEFAULT_RANGE = (0.1, 10.0)


@dataclass(frozen=True)
class ThetaAction:
    """The log-scale map of an action component onto ``[theta_min, theta_max]``."""

    theta_min: float
    theta_max: float

    def theta(self, a: NDArray[np.float64]) -> NDArray[np.float64]:
        """Scores (...) of action components (...), clipped to [-1, 1] first."""
        t = 0.5 * (np.clip(a, -1.0, 1.0) + 1.0)
        lo, hi = np.log(self.theta_min), np.log(self.theta_max)
        return np.exp(lo + t * (hi - lo))

    def step_theta(self, a: NDArray, current: NDArray[np.float64]) -> NDArray[np.float64]:
        """The scores (...) of a step's action components (...): ``theta``, except that a
        component equal, at the action space's float32 resolution, to the one the current score
        maps to keeps that score (clipped to the range) exactly. An action in float32 cannot
        name a score more finely, and this is what ``action`` promises the scripted
        controller: its component keeps each agent's theta, with no drift of a rounding."""
        keep = np.float32(a) == self.action(current).astype(np.float32)
        kept = np.clip(current, self.theta_min, self.theta_max)
        return np.where(keep, kept, self.theta(a))

    def action(self, theta: NDArray[np.float64]) -> NDArray[np.float64]:
        """The action components (...) that give the scores ``theta`` (...), clipped to the
        range: the inverse of ``theta``. A zero range maps to 0."""
        lo, hi = np.log(self.theta_min), np.log(self.theta_max)
        if hi == lo:
            return np.zeros(np.shape(theta))
        log = np.log(np.clip(theta, self.theta_min, self.theta_max))
        return 2.0 * (log - lo) / (hi - lo) - 1.0


def theta_action_of(enabled: Any, theta_range: Any, theta_max: float) -> ThetaAction | None:
    """The map for keywords ``theta_action`` (a flag) and ``theta_action_range`` ((low, high),
    0 < low <= high <= the scenario's ``theta_max``; None: ``DEFAULT_RANGE``), checked."""
    if not check_flag(enabled, "theta_action"):
        if theta_range is not None:
            raise TypeError("theta_action_range needs theta_action=True")
        return None
    value = DEFAULT_RANGE if theta_range is None else theta_range
    return ThetaAction(*check_theta_interval(value, "theta_action_range", theta_max))
