"""Episode metrics (DESIGN.md section 6), counted in steps.

* deadlock onset: first step the right-hand rule fires for any agent;
* deadlock resolved: first step every agent has passed the midpoint of its start-goal segment;
* completed: first step all agents are at their goals;
* the paper's average minimum distance D over time (Fig. 7): the mean over agents of the
  distance to the nearest neighbour, per step;
* path length and deviation from the nominal controller per agent.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray


def passed_midpoint(
    positions: NDArray[np.float64], starts: NDArray[np.float64], goals: NDArray[np.float64]
) -> NDArray[np.bool_]:
    """Agents whose projection on their start-goal segment is past its middle."""
    seg = goals - starts
    progress = np.einsum("ij,ij->i", positions - starts, seg)
    return progress >= 0.5 * np.einsum("ij,ij->i", seg, seg)


def resolution_gain(
    onset_sym: int, resolved_sym: int, onset_asym: int, resolved_asym: int
) -> float:
    """``1 - (resolved - onset)_asym / (resolved - onset)_sym`` (DESIGN.md section 6)."""
    return 1.0 - (resolved_asym - onset_asym) / (resolved_sym - onset_sym)


def completion_gain(completed_sym: int, completed_asym: int) -> float:
    """``1 - completed_asym / completed_sym``."""
    return 1.0 - completed_asym / completed_sym


def _first(step: int | None, condition: bool, t: int) -> int | None:
    return t if step is None and condition else step


@dataclass
class EpisodeMetrics:
    """Accumulates one episode, step by step, without keeping more than per-agent sums and the
    per-step series the paper plots."""

    n: int
    dt: float
    safety_radius: float
    steps: int = 0
    deadlock_onset: int | None = None
    deadlock_resolved: int | None = None
    completed: int | None = None
    min_distance: float = float("inf")
    n_collision_steps: int = 0
    n_infeasible: int = 0
    n_unrecoverable_pairs: int = 0
    n_capped_shares: int = 0
    min_barrier: float = float("inf")
    path_length: NDArray[np.float64] = field(init=False)
    deviation: NDArray[np.float64] = field(init=False)
    arrival: NDArray[np.int64] = field(init=False)
    min_distance_series: list[float] = field(default_factory=list)
    avg_min_distance_series: list[float] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.path_length = np.zeros(self.n)
        self.deviation = np.zeros(self.n)
        self.arrival = np.full(self.n, -1, dtype=np.int64)

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
        """Record the state after one more step."""
        self.steps += 1
        t = self.steps
        self.path_length += np.linalg.norm(displacement, axis=1)
        self.deviation += np.linalg.norm(applied - requested, axis=1) * self.dt
        step_min = float(nearest.min())
        self.min_distance = min(self.min_distance, step_min)
        self.min_distance_series.append(step_min)
        self.avg_min_distance_series.append(float(nearest.mean()))
        self.n_collision_steps += int(step_min < self.safety_radius - 1e-9)
        self.deadlock_onset = _first(self.deadlock_onset, bool(rh_active.any()), t)
        self.deadlock_resolved = _first(self.deadlock_resolved, bool(passed_mid.all()), t)
        self.completed = _first(self.completed, bool(at_goal.all()), t)
        self.arrival = np.where((self.arrival < 0) & at_goal, t, self.arrival)
        if filter_stats is not None:
            self.n_infeasible += int(np.sum(~filter_stats["feasible"]))
            self.n_unrecoverable_pairs += int(filter_stats["n_unrecoverable_pairs"])
            self.n_capped_shares += int(filter_stats["n_capped_shares"])
            self.min_barrier = min(self.min_barrier, float(filter_stats["min_h"]))

    def summary(self) -> dict[str, Any]:
        """The episode's metrics as plain Python values and arrays."""
        return {
            "steps": self.steps,
            "success": self.completed is not None,
            "deadlock_onset": self.deadlock_onset,
            "deadlock_resolved": self.deadlock_resolved,
            "completed": self.completed,
            "min_distance": self.min_distance,
            "n_collision_steps": self.n_collision_steps,
            "n_infeasible": self.n_infeasible,
            "n_unrecoverable_pairs": self.n_unrecoverable_pairs,
            "n_capped_shares": self.n_capped_shares,
            "min_barrier": self.min_barrier,
            "path_length": self.path_length.copy(),
            "deviation": self.deviation.copy(),
            "arrival": self.arrival.copy(),
            "min_distance_series": np.array(self.min_distance_series),
            "avg_min_distance_series": np.array(self.avg_min_distance_series),
        }
