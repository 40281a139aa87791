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
from numba import njit
from numpy.typing import NDArray


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
    # agents that have reached their goals (at least once) so far, and the makespan: the step
    # the last of them first reached it (-1 until all have)
    ("arrived", np.int64),
    ("makespan", np.int64),
)


@njit(cache=True)
def accumulate_step(
    counts,
    min_distance,
    infeasible,
    sums,
    arrival,
    min_barrier,
    before,
    after,
    starts,
    goals,
    applied,
    requested,
    nearest,
    rh,
    at_goal,
    feasible,
    min_h,
    dt,
    collision_below,
    series,
    contact,
):
    """One step of every env: counters, first-event steps, per-agent sums (see ``update``).
    A collision step has some ``contact[e, i] < collision_below`` (``contact`` the nearest
    distance itself, or ``rsvo_env.geometry.clearance.contact`` with the threshold 1 - 1e-9).

    counts[e] = (steps, deadlock_onset, deadlock_resolved, completed, collision_steps);
    sums[e, i] = (path length, deviation); ``feasible`` and ``min_h`` are empty without filter;
    series[e] = (the step's smallest and mean nearest distance).
    """
    E, n = nearest.shape
    filtered = feasible.shape[0] == E
    for e in range(E):
        counts[e, 0] += 1
        t = counts[e, 0]
        step_min, step_sum, closest = np.inf, 0.0, np.inf
        any_rh, all_mid, all_goal = False, True, True
        for i in range(n):
            dx, dy = after[e, i, 0] - before[e, i, 0], after[e, i, 1] - before[e, i, 1]
            sums[e, i, 0] += np.sqrt(dx * dx + dy * dy)
            ux = applied[e, i, 0] - requested[e, i, 0]
            uy = applied[e, i, 1] - requested[e, i, 1]
            sums[e, i, 1] += np.sqrt(ux * ux + uy * uy) * dt
            step_min = min(step_min, nearest[e, i])
            step_sum += nearest[e, i]
            closest = min(closest, contact[e, i])
            any_rh = any_rh or rh[e, i]
            # past the middle of its start-goal segment: its projection on it beyond half-way
            sx, sy = goals[e, i, 0] - starts[e, i, 0], goals[e, i, 1] - starts[e, i, 1]
            px, py = after[e, i, 0] - starts[e, i, 0], after[e, i, 1] - starts[e, i, 1]
            all_mid = all_mid and (px * sx + py * sy >= 0.5 * (sx * sx + sy * sy))
            all_goal = all_goal and at_goal[e, i]
            if arrival[e, i] < 0 and at_goal[e, i]:
                arrival[e, i] = t
            if filtered and not feasible[e, i]:
                infeasible[e] += 1
        min_distance[e] = min(min_distance[e], step_min)
        series[e, 0], series[e, 1] = step_min, step_sum / n
        counts[e, 4] += closest < collision_below
        for col, event in ((1, any_rh), (2, all_mid), (3, all_goal)):
            if counts[e, col] < 0 and event:
                counts[e, col] = t
        if filtered:
            min_barrier[e] = min(min_barrier[e], min_h[e])


_NO_FEASIBLE = np.ones((0, 0), dtype=np.bool_)
_NO_MIN_H = np.zeros(0)


@njit(cache=True)
def _arrivals(arrival):
    """(agents arrived, makespan: the last first arrival, -1 until every agent has) of one
    env's first-arrival steps (N,), -1 where not yet."""
    count, last = 0, -1
    for i in range(arrival.shape[0]):
        if arrival[i] >= 0:
            count += 1
            last = max(last, arrival[i])
    return count, last if count == arrival.shape[0] else -1


@njit(cache=True)
def _flat(counts, min_distance, infeasible, arrival):
    """The ``FLAT_FIELDS`` arrays (E,), fresh, in one pass (a step's infos carry them)."""
    E = arrival.shape[0]
    success = np.empty(E, dtype=np.bool_)
    arrived = np.empty(E, dtype=np.int64)
    makespan = np.empty(E, dtype=np.int64)
    for e in range(E):
        arrived[e], makespan[e] = _arrivals(arrival[e])
        success[e] = counts[e, 3] >= 0
    steps, completed, collisions = counts[:, 0].copy(), counts[:, 3].copy(), counts[:, 4].copy()
    return (
        steps,
        success,
        completed,
        min_distance.copy(),
        collisions,
        infeasible.copy(),
        arrived,
        makespan,
    )


@njit(cache=True)
def _add_counts(unrecoverable, more_unrecoverable, capped, more_capped):
    """The filter's per-env counts added in place: one compiled call, a fifth of two numpy
    additions' cost at one env (every step)."""
    unrecoverable += more_unrecoverable
    capped += more_capped


@njit(cache=True)
def _flat_row(counts, min_distance, infeasible, arrival, e):
    """Env e's ``_flat`` values as scalars, in ``FLAT_FIELDS`` order."""
    arrived, makespan = _arrivals(arrival[e])
    return (
        counts[e, 0],
        counts[e, 3] >= 0,
        counts[e, 3],
        min_distance[e],
        counts[e, 4],
        infeasible[e],
        arrived,
        makespan,
    )


class EpisodeMetrics:
    """Accumulates the running episode of each of E envs in (E,) and (E, N) arrays, without
    keeping more than per-agent sums; with ``record_series`` (one env only) also the per-step
    series the paper plots. Steps without an event keep -1 (``None`` in ``summary``)."""

    def __init__(
        self, num_envs: int, n: int, dt: float, safety_radius: float, record_series: bool = False
    ) -> None:
        if record_series and num_envs != 1:
            raise ValueError("record_series needs num_envs = 1")
        self.num_envs, self.n, self.dt, self.safety_radius = num_envs, n, dt, safety_radius
        self.record_series = record_series
        # a nearest distance below this is a collision step
        self.collision_below = safety_radius * (1.0 - COLLISION_TOL)
        E = num_envs
        self.counts = np.zeros((E, 5), dtype=np.int64)
        self.min_distance = np.full(E, np.inf)
        self.infeasible = np.zeros(E, dtype=np.int64)
        self.unrecoverable_pairs = np.zeros(E, dtype=np.int64)
        self.capped_shares = np.zeros(E, dtype=np.int64)
        self.min_barrier = np.full(E, np.inf)
        self.sums = np.zeros((E, n, 2))
        self.arrival = np.full((E, n), -1, dtype=np.int64)
        # the last step's smallest and mean nearest distance of each env
        self.step_series = np.zeros((E, 2))
        self.min_distance_series: list[float] = []
        self.avg_min_distance_series: list[float] = []

    # Named columns of the packed arrays, taken afresh at each read: a view kept as an attribute
    # would come unhooked from its base in a copy (deepcopy and pickle copy each array alone),
    # and the copy's counters would stop counting.
    steps = property(lambda self: self.counts[:, 0])
    deadlock_onset = property(lambda self: self.counts[:, 1])
    deadlock_resolved = property(lambda self: self.counts[:, 2])
    completed = property(lambda self: self.counts[:, 3])
    collision_steps = property(lambda self: self.counts[:, 4])
    path_length = property(lambda self: self.sums[..., 0])
    deviation = property(lambda self: self.sums[..., 1])

    def reset(self, envs: NDArray[np.int64]) -> None:
        """Start a new episode in the given envs."""
        self.counts[envs] = (0, -1, -1, -1, 0)
        for name, value in (
            ("min_distance", np.inf),
            ("infeasible", 0),
            ("unrecoverable_pairs", 0),
            ("capped_shares", 0),
            ("min_barrier", np.inf),
            ("sums", 0.0),
            ("arrival", -1),
        ):
            getattr(self, name)[envs] = value
        if self.record_series:
            self.min_distance_series.clear()
            self.avg_min_distance_series.clear()

    def update(
        self,
        before: NDArray[np.float64],
        after: NDArray[np.float64],
        starts: NDArray[np.float64],
        goals: NDArray[np.float64],
        nearest: NDArray[np.float64],
        rh_active: NDArray[np.bool_],
        at_goal: NDArray[np.bool_],
        requested: NDArray[np.float64],
        applied: NDArray[np.float64],
        filter_stats: dict[str, Any] | None = None,
        contact: NDArray[np.float64] | None = None,
    ) -> None:
        """Record one more step of every env (arrays (E, N, ...)): positions before and after,
        the state's derived signals, the requested and the applied controls, the filter's stats;
        ``contact``: ``rsvo_env.geometry.clearance.contact`` where bodies differ or obstacles
        stand
        (collisions are then counted on it)."""
        feasible, min_h = self.begin(filter_stats)
        measure, below = self.collision_measure(nearest, contact)
        accumulate_step(
            self.counts,
            self.min_distance,
            self.infeasible,
            self.sums,
            self.arrival,
            self.min_barrier,
            before,
            after,
            starts,
            goals,
            applied,
            requested,
            nearest,
            rh_active,
            at_goal,
            feasible,
            min_h,
            self.dt,
            below,
            self.step_series,
            measure,
        )
        self.end()

    def collision_measure(
        self, nearest: NDArray[np.float64], contact: NDArray[np.float64] | None
    ) -> tuple[NDArray[np.float64], float]:
        """What a collision is read on, and below what: the nearest distance below the safety
        radius less the relative round-off margin, or, where bodies differ or obstacles stand,
        the ``contact`` ratio below 1 less that margin."""
        if contact is None:
            return nearest, self.collision_below
        return contact, 1.0 - COLLISION_TOL

    def begin(self, filter_stats: dict[str, Any] | None) -> tuple[NDArray, NDArray]:
        """The part of ``update`` before its kernel (``accumulate_step``): the filter's counts
        added; returns the kernel's ``feasible`` and ``min_h`` arguments."""
        if filter_stats is None:
            return _NO_FEASIBLE, _NO_MIN_H
        _add_counts(
            self.unrecoverable_pairs,
            filter_stats["n_unrecoverable_pairs"],
            self.capped_shares,
            filter_stats["n_capped_shares"],
        )
        return filter_stats["feasible"], filter_stats["min_h"]

    def end(self) -> None:
        """The part of ``update`` after its kernel: the per-step series, when recorded."""
        if self.record_series:
            self.min_distance_series.append(float(self.step_series[0, 0]))
            self.avg_min_distance_series.append(float(self.step_series[0, 1]))

    def flat(self) -> dict[str, NDArray]:
        """(E,) arrays ``episode_<field>`` of the running episodes (final on their last step)."""
        values = _flat(self.counts, self.min_distance, self.infeasible, self.arrival)
        return {f"episode_{k}": v for (k, _), v in zip(FLAT_FIELDS, values, strict=True)}

    def flat_row(self, e: int = 0) -> tuple:
        """Env e's ``flat`` values, in ``FLAT_FIELDS`` order, as Python scalars."""
        # one compiled call: a step's infos read this row, at small N a good part of the step
        return _flat_row(self.counts, self.min_distance, self.infeasible, self.arrival, e)

    def summary(self, e: int = 0) -> dict[str, Any]:
        """Env e's episode as plain Python values and arrays."""

        def step(x: NDArray) -> int | None:
            return None if x[e] < 0 else int(x[e])

        arrived, makespan = _arrivals(self.arrival[e])
        out = {
            "steps": int(self.steps[e]),
            "success": bool(self.completed[e] >= 0),
            "deadlock_onset": step(self.deadlock_onset),
            "deadlock_resolved": step(self.deadlock_resolved),
            "completed": step(self.completed),
            "makespan": None if makespan < 0 else makespan,
            "arrived": arrived,
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
