"""Episode metrics (``docs/metrics.md``), counted in steps, for E envs at once.

* deadlock onset: first step the right-hand rule fires for any agent;
* deadlock resolved: first step every agent has passed the midpoint of its start-goal segment;
* completed: first step all agents are at their goals;
* the paper's average minimum distance D over time (Fig. 7): the mean over agents of the
  distance to the nearest neighbour, per step;
* path length and deviation from the nominal controller per agent.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray


def passed_midpoint(
    positions: NDArray[np.float64], starts: NDArray[np.float64], goals: NDArray[np.float64]
) -> NDArray[np.bool_]:
    """Agents whose projection on their start-goal segment is past its middle."""
    seg = goals - starts
    progress = np.einsum("...j,...j->...", positions - starts, seg)
    return progress >= 0.5 * np.einsum("...j,...j->...", seg, seg)


def resolution_gain(
    onset_sym: int, resolved_sym: int, onset_asym: int, resolved_asym: int
) -> float:
    """``1 - (resolved - onset)_asym / (resolved - onset)_sym``."""
    return 1.0 - (resolved_asym - onset_asym) / (resolved_sym - onset_sym)


def completion_gain(completed_sym: int, completed_asym: int) -> float:
    """``1 - completed_asym / completed_sym``."""
    return 1.0 - completed_asym / completed_sym


# Relative margin of the collision test: a distance below R (1 - COLLISION_TOL) is a collision,
# so an exactly safe step that rounds a few ulps below R does not count, in any units.
COLLISION_TOL = 1e-9

# Per-env counters reported in step infos under "episode_<name>" (flat, same keys every step).
FLAT_FIELDS = (
    ("steps", np.int64),
    ("success", np.bool_),
    ("completed", np.int64),
    ("min_distance", np.float64),
    ("collision_steps", np.int64),
    ("infeasible", np.int64),
)


def collided(distance: NDArray[np.float64], safety_radius: float) -> NDArray[np.bool_]:
    """Distances below the safety radius, less the relative round-off margin."""
    return distance < safety_radius * (1.0 - COLLISION_TOL)


class EpisodeMetrics:
    """Accumulates the running episode of each of E envs in (E,) and (E, N) arrays, without
    keeping more than per-agent sums; with ``record_series`` (one env only) also the per-step
    series the paper plots. Steps without an event keep -1 (``None`` in :meth:`summary`)."""

    def __init__(
        self, num_envs: int, n: int, dt: float, safety_radius: float, record_series: bool = False
    ) -> None:
        if record_series and num_envs != 1:
            raise ValueError("record_series needs num_envs = 1")
        self.num_envs, self.n, self.dt, self.safety_radius = num_envs, n, dt, safety_radius
        self.record_series = record_series
        E = num_envs
        self.steps = np.zeros(E, dtype=np.int64)
        self.deadlock_onset = np.full(E, -1, dtype=np.int64)
        self.deadlock_resolved = np.full(E, -1, dtype=np.int64)
        self.completed = np.full(E, -1, dtype=np.int64)
        self.min_distance = np.full(E, np.inf)
        self.collision_steps = np.zeros(E, dtype=np.int64)
        self.infeasible = np.zeros(E, dtype=np.int64)
        self.unrecoverable_pairs = np.zeros(E, dtype=np.int64)
        self.capped_shares = np.zeros(E, dtype=np.int64)
        self.min_barrier = np.full(E, np.inf)
        self.path_length = np.zeros((E, n))
        self.deviation = np.zeros((E, n))
        self.arrival = np.full((E, n), -1, dtype=np.int64)
        self.min_distance_series: list[float] = []
        self.avg_min_distance_series: list[float] = []

    def reset(self, envs: NDArray[np.int64]) -> None:
        """Start a new episode in the given envs."""
        for name, value in (
            ("steps", 0),
            ("deadlock_onset", -1),
            ("deadlock_resolved", -1),
            ("completed", -1),
            ("min_distance", np.inf),
            ("collision_steps", 0),
            ("infeasible", 0),
            ("unrecoverable_pairs", 0),
            ("capped_shares", 0),
            ("min_barrier", np.inf),
            ("path_length", 0.0),
            ("deviation", 0.0),
            ("arrival", -1),
        ):
            getattr(self, name)[envs] = value
        if self.record_series:
            self.min_distance_series.clear()
            self.avg_min_distance_series.clear()

    def update(
        self,
        displacement: NDArray[np.float64],
        nearest: NDArray[np.float64],
        rh_active: NDArray[np.bool_],
        passed_mid: NDArray[np.bool_],
        at_goal: NDArray[np.bool_],
        requested: NDArray[np.float64],
        applied: NDArray[np.float64],
        filter_stats: dict[str, Any] | None = None,
    ) -> None:
        """Record the state after one more step of every env (arrays (E, N, ...))."""
        self.steps += 1
        t = self.steps
        self.path_length += np.linalg.norm(displacement, axis=-1)
        self.deviation += np.linalg.norm(applied - requested, axis=-1) * self.dt
        step_min = nearest.min(axis=-1)
        np.minimum(self.min_distance, step_min, out=self.min_distance)
        if self.record_series:
            self.min_distance_series.append(float(step_min[0]))
            self.avg_min_distance_series.append(float(nearest[0].mean()))
        self.collision_steps += collided(step_min, self.safety_radius)
        for name, condition in (
            ("deadlock_onset", rh_active.any(axis=-1)),
            ("deadlock_resolved", passed_mid.all(axis=-1)),
            ("completed", at_goal.all(axis=-1)),
        ):
            first = getattr(self, name)
            first[(first < 0) & condition] = t[(first < 0) & condition]
        self.arrival = np.where((self.arrival < 0) & at_goal, t[:, None], self.arrival)
        if filter_stats is not None:
            self.infeasible += (~filter_stats["feasible"]).sum(axis=-1)
            self.unrecoverable_pairs += filter_stats["n_unrecoverable_pairs"]
            self.capped_shares += filter_stats["n_capped_shares"]
            np.minimum(self.min_barrier, filter_stats["min_h"], out=self.min_barrier)

    def flat(self) -> dict[str, NDArray]:
        """(E,) arrays ``episode_<field>`` of the running episodes (final on their last step)."""
        values = {
            "steps": self.steps,
            "success": self.completed >= 0,
            "completed": self.completed,
            "min_distance": self.min_distance,
            "collision_steps": self.collision_steps,
            "infeasible": self.infeasible,
        }
        return {f"episode_{k}": values[k].astype(dtype) for k, dtype in FLAT_FIELDS}

    def summary(self, e: int = 0) -> dict[str, Any]:
        """Env e's episode as plain Python values and arrays."""

        def step(x: NDArray) -> int | None:
            return None if x[e] < 0 else int(x[e])

        out = {
            "steps": int(self.steps[e]),
            "success": bool(self.completed[e] >= 0),
            "deadlock_onset": step(self.deadlock_onset),
            "deadlock_resolved": step(self.deadlock_resolved),
            "completed": step(self.completed),
            "min_distance": float(self.min_distance[e]),
            "n_collision_steps": int(self.collision_steps[e]),
            "n_infeasible": int(self.infeasible[e]),
            "n_unrecoverable_pairs": int(self.unrecoverable_pairs[e]),
            "n_capped_shares": int(self.capped_shares[e]),
            "min_barrier": float(self.min_barrier[e]),
            "path_length": self.path_length[e].copy(),
            "deviation": self.deviation[e].copy(),
            "arrival": self.arrival[e].copy(),
        }
        if self.record_series:
            out["min_distance_series"] = np.array(self.min_distance_series)
            out["avg_min_distance_series"] = np.array(self.avg_min_distance_series)
        return out
