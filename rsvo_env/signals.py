"""The per-agent signals of a step (the infos' per-agent fields), defined once for every adapter."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from rsvo_env.metrics import COLLISION_TOL, collided

if TYPE_CHECKING:
    from rsvo_env.core import Simulator


def signals(
    sim: Simulator,
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
    out = {
        "u_nominal": u_nominal,
        "u_safe": u_safe,
        "intervention": intervention,
        "feasible": stats["feasible"],
        "active_constraints": stats["active"],
        "max_violation": stats["max_violation"],
        "min_distance": s.nearest,
        "cost": (
            collided(s.nearest, sim.safety_radius)
            if s.contact is None
            else s.contact < 1.0 - COLLISION_TOL
        ).astype(np.float64),
        "at_goal": s.at_goal,
        "rh_active": s.rh_active,
        "deadlocked": sim.progress.stalled(sim.deadlock_window, s.at_goal),
    }
    if sim.theta_action is not None:
        out["theta"] = s.theta.copy()
    return out
