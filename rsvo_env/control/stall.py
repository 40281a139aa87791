"""The stall clock: how long each agent has gone without coming closer to its goal.

A memoryless policy in a configuration that does not change (two agents each waiting for the
other, an agent holding still short of its goal) outputs the same action at every step, for
ever. The clock is an observed value that keeps moving exactly there, so a policy can learn to
leave such fixed points (``Simulator(stall_clock=...)``; off by default).

An agent makes progress when its distance to its goal falls below the least distance it has had
since it last made progress, by at least ``PROGRESS`` safety radii (a relative step, so the
clock reads the same in any unit of length). An agent at its goal is not stalled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env.util import planar
from rsvo_env.util.validation import check_count, shown

PROGRESS = 0.02  # safety radii closer to the goal that count as progress
# an agent short of its goal that has made no progress for this long is deadlocked
# (docs/metrics.md): longer than any wait for a neighbour to pass at the crowds' speeds
DEADLOCK_SECONDS = 10.0


# the most steps a duration may last: step counts are int64 in the compiled stages, and every
# count up to 2**53 is exact in a float
MAX_STEPS = 2**53


def check_dt(dt: float, name: str) -> float:
    """``dt`` (already checked finite and > 0) refused where the deadlock window,
    ``DEADLOCK_SECONDS``, would last more than ``MAX_STEPS`` steps: no step count of the env
    could hold it (``ValueError`` naming ``name``)."""
    if DEADLOCK_SECONDS / dt > MAX_STEPS:
        raise ValueError(
            f"{name} = {shown(dt)} is too small: the deadlock window of {DEADLOCK_SECONDS} s would "
            f"last more than 2**53 steps (dt >= {DEADLOCK_SECONDS / MAX_STEPS:.3g} s)"
        )
    return dt


def deadlock_steps(dt: float) -> int:
    """The deadlock window in steps of ``dt``: the fewest steps that last ``DEADLOCK_SECONDS``
    (at least one), so no agent is flagged before then (a rounding of the quotient, as at
    dt = 0.1, is not a step more)."""
    return max(1, math.ceil(DEADLOCK_SECONDS / dt * (1.0 - 1e-12)))


@dataclass
class StallClock:
    """Per agent (E, N): the distance to beat (``best``) and the steps since the last progress.
    The observed value is ``steps / unit`` (``unit``: steps)."""

    unit: int
    best: NDArray[np.float64]
    steps: NDArray[np.int64]

    @classmethod
    def create(cls, unit: int, num_envs: int, n: int) -> StallClock:
        unit = check_count(unit, "stall_clock", 1)
        return cls(unit, np.full((num_envs, n), np.inf), np.zeros((num_envs, n), dtype=np.int64))

    def reset(self, envs: NDArray[np.int64], distance: NDArray[np.float64]) -> None:
        """New episodes in ``envs``; ``distance`` (len(envs), N) to the goals at the start."""
        self.best[envs] = distance
        self.steps[envs] = 0

    def tick(
        self,
        positions: NDArray[np.float64],
        goals: NDArray[np.float64],
        at_goal: NDArray[np.bool_],
        safety_radius: float,
    ) -> None:
        """One step of every env: ``positions`` and ``goals`` (E, N, 2) after it."""
        tick_clocks(positions, goals, at_goal, PROGRESS * safety_radius, self.best, self.steps)

    def value(self, envs: NDArray[np.int64] | slice = slice(None)) -> NDArray[np.float64]:
        """The observed clock (E, N) (of ``envs``): steps stalled over ``unit``."""
        return self.steps[envs] / self.unit

    def bound(self, max_steps: int) -> float:
        """The largest value an episode of ``max_steps`` steps can show."""
        return max_steps / self.unit


@njit(cache=True)
def tick_clocks(x, goals, at_goal, margin, best, steps):
    """In place: an agent that came ``margin`` closer than its best (or is at its goal) starts
    its clock again from its new best; every other agent's clock advances. The distance is
    ``goal_distance``'s arithmetic, computed here: one call a step, not three."""
    E, n = at_goal.shape
    for e in range(E):
        for i in range(n):
            dx, dy = goals[e, i, 0] - x[e, i, 0], goals[e, i, 1] - x[e, i, 1]
            distance = np.sqrt(dx * dx + dy * dy)
            if distance <= best[e, i] - margin or at_goal[e, i]:
                best[e, i] = distance
                steps[e, i] = 0
            else:
                steps[e, i] += 1


@njit(cache=True)
def stalled(steps: NDArray, window: int, at_goal: NDArray) -> NDArray[np.bool_]:
    """(E, N) agents short of their goals with no progress (``steps``, the clock's) for
    ``window`` steps or more; compiled, so the step's signals call it from compiled code."""
    return (steps >= window) & ~at_goal


def goal_distance(positions: NDArray[np.float64], goals: NDArray[np.float64]) -> NDArray:
    """Each agent's distance to its goal, (..., N)."""
    return planar.norm(goals - positions)


def held(no_progress: NDArray[np.int64] | None, dt: float, seconds: float) -> NDArray | None:
    """(E, N): the agents that have come no closer to their goals for ``seconds`` or more, read
    from the state's ``no_progress`` (steps of ``dt``); None where the state carries no clock."""
    return None if no_progress is None else no_progress * dt >= seconds
