"""The per-agent signals of a step (the infos' per-agent fields), defined once for every adapter."""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env.control.stall import stalled
from rsvo_env.sim.view import SimulatorView


def signals(
    sim: SimulatorView,
    u_nominal: NDArray | None = None,
    u_safe: NDArray | None = None,
    intervention: NDArray | None = None,
    stats: dict | None = None,
) -> dict[str, NDArray]:
    """Per-agent signals (E, N, ...), the same keys, dtypes and shapes at reset (controls zero,
    no filter work) and at every step; with theta actions, each agent's ``theta`` in force."""
    s = sim.state
    E, n = s.theta.shape
    if u_nominal is None or u_safe is None or intervention is None:
        u_nominal = u_safe = np.zeros((E, n, 2))
        intervention = np.zeros((E, n))
    if stats is None:  # no filter work: feasible, nothing active, no violation
        stats = {
            "feasible": np.ones((E, n), dtype=bool),
            "active": np.zeros((E, n), dtype=np.int64),
            "max_violation": np.zeros((E, n)),
        }
    measure, below = sim.metrics.collision_measure(s.nearest, s.contact)
    cost, deadlocked = _flags(measure, below, sim.progress.steps, sim.deadlock_window, s.at_goal)
    out = {
        "u_nominal": u_nominal,
        "u_safe": u_safe,
        "intervention": intervention,
        "feasible": stats["feasible"],
        "active_constraints": stats["active"],
        "max_violation": stats["max_violation"],
        "min_distance": s.nearest,
        "cost": cost,
        "at_goal": s.at_goal,
        "rh_active": s.rh_active,
        "deadlocked": deadlocked,
    }
    if sim.theta_action is not None:
        out["theta"] = s.theta.copy()
    return out


@njit(cache=True)
def _flags(measure, below, steps, window, at_goal):
    """The ``cost`` (1.0 on a collision) and ``deadlocked`` signals in one compiled call: as
    numpy operations on a few agents they cost more than the rest of the signals."""
    return (measure < below).astype(np.float64), stalled(steps, window, at_goal)
