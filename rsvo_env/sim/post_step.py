"""What follows integration in the core's step: the derived state, the metrics, the reward.

After the positions move, the step derives the nearest distance, the K nearest neighbours, who
is at its goal and whom the right-hand rule turns; records the step in the episode metrics;
marks first arrivals; computes the reward terms and which envs terminated; advances the stall
clock (``rsvo_env.control.stall``). For a scenario with
the base hooks (``Scenario.at_goal``, ``right_hand_active``, ``reward``) and few agents all of it
is one compiled call of the same kernels (``in_one_call``), so a small env pays one dispatch
instead of a dozen; otherwise the hooks are called in turn (``hook_by_hook``). Both give the
same numbers, bit for bit (tested).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env.control.nominal import right_hand_active
from rsvo_env.control.stall import PROGRESS, tick_clocks
from rsvo_env.geometry.clearance import contact
from rsvo_env.scenarios.base import Scenario, reward_terms
from rsvo_env.sim.metrics import accumulate_step
from rsvo_env.sim.view import SimulatorView
from rsvo_env.util import sizes
from rsvo_env.util.neighbors import knn_dense_arrays, nearest_neighbors
from rsvo_env.util.planar import within_distance

_HOOKS = ("at_goal", "right_hand_active", "reward")


def one_call_serves(scenario: Scenario, n: int) -> bool:
    """Whether ``in_one_call`` serves this scenario: its hooks are the base ones, and N is small
    enough for the dense neighbour search."""
    base = all(getattr(type(scenario), h) is getattr(Scenario, h) for h in _HOOKS)
    return base and scenario.plain and 2 <= n <= sizes.ALL_PAIRS_MAX_AGENTS


def derive(sim: SimulatorView, envs: NDArray[np.int64] | None = None) -> None:
    """The derived state of the current positions, through the scenario's hooks; with ``envs``
    (the envs a reset moved) only theirs where the hooks are the base ones."""
    s = sim.state
    part = envs is not None and sim.post_step_in_one_call and len(envs) < len(s.nearest)
    pick = envs if part else slice(None)
    x = s.positions[pick]
    d, idx = nearest_neighbors(x, max(sim.k, 1))
    derived = (d[..., 0], idx[..., : sim.k], sim.scenario.at_goal(x, s.goals[pick]))
    if part:
        # new arrays, not writes into the old: the last step's infos hold those
        fresh = [old.copy() for old in (s.nearest, s.neighbors, s.at_goal)]
        for whole, new in zip(fresh, derived, strict=True):
            whole[pick] = new
        derived = tuple(fresh)
    s.nearest, s.neighbors, s.at_goal = derived
    s.rh_active = sim.scenario.right_hand_active(s)
    if not sim.plain:
        s.contact = contact(s.positions, sim.radii, s.obstacles)


def hook_by_hook(
    sim: SimulatorView, before: NDArray, requested: NDArray, applied: NDArray, stats: Any
) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_]]:
    """The after-integration stage through the scenario's hooks: reward (E, N), terminated
    (every agent at its goal) and truncated (not terminated, and the step limit reached); the
    stall clock advanced."""
    s = sim.state
    derive(sim)
    at_goal = s.at_goal
    sim.metrics.update(
        before,
        s.positions,
        s.starts,
        s.goals,
        s.nearest,
        s.rh_active,
        at_goal,
        requested,
        applied,
        stats,
        s.contact,
    )
    first_arrival, terminated, truncated = _episode_end(
        at_goal, s.reached, sim.metrics.counts, sim.max_steps
    )
    reward = sim.scenario.reward(before, s.positions, s.goals, first_arrival, sim.reward_weights)
    sim.progress.tick(s.positions, s.goals, at_goal, sim.safety_radius)
    return reward, terminated, truncated


@njit(cache=True)
def _episode_end(at_goal, reached, counts, max_steps):
    """First arrivals (marked in ``reached``), terminated envs (every agent at its goal) and
    truncated ones (not terminated, ``max_steps`` reached): the one definition both paths use."""
    E, n = at_goal.shape
    first = np.empty((E, n), dtype=np.bool_)
    terminated = np.ones(E, dtype=np.bool_)
    truncated = np.empty(E, dtype=np.bool_)
    for e in range(E):
        for i in range(n):
            first[e, i] = at_goal[e, i] and not reached[e, i]
            reached[e, i] = reached[e, i] or at_goal[e, i]
            terminated[e] = terminated[e] and at_goal[e, i]
        truncated[e] = not terminated[e] and counts[e, 0] >= max_steps
    return first, terminated, truncated


@njit(cache=True)
def _in_one_call(
    x,
    before,
    goals,
    starts,
    reached,
    k,
    tol,
    rh_on,
    trigger,
    rh_hold,
    weights,
    counts,
    min_distance,
    infeasible,
    sums,
    arrival,
    min_barrier,
    applied,
    requested,
    feasible,
    min_h,
    dt,
    collision_below,
    series,
    max_steps,
    margin,
    best,
    stalled_steps,
    nearest,
    neighbors,
    at_goal,
    rh,
    reward,
    terminated,
    truncated,
):
    """``hook_by_hook`` with the base hooks, as one compiled pass of the same kernels, into the
    given outputs (allocated by the caller: arrays a compiled call returns cost more each)."""
    E, n = x.shape[0], x.shape[1]
    dist, idx = knn_dense_arrays(x, max(k, 1))
    for e in range(E):
        for i in range(n):
            nearest[e, i] = dist[e, i, 0]
            for c in range(k):
                neighbors[e, i, c] = idx[e, i, c]
    at_goal[:] = within_distance(x, goals, tol)
    if rh_on:
        # Scenario.right_hand_active's, on the clock before this tick
        rh[:] = right_hand_active(nearest, at_goal, trigger, stalled_steps, dt, rh_hold)
    else:
        rh[:] = False
    accumulate_step(
        counts,
        min_distance,
        infeasible,
        sums,
        arrival,
        min_barrier,
        before,
        x,
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
        nearest,
    )
    first, term, trunc = _episode_end(at_goal, reached, counts, max_steps)
    terminated[:] = term
    truncated[:] = trunc
    reward_terms(
        before.reshape(-1, 2),
        x.reshape(-1, 2),
        goals.reshape(-1, 2),
        first.reshape(-1),
        weights[0],
        weights[1],
        weights[2],
        reward.reshape(-1),
    )
    tick_clocks(x, goals, at_goal, margin, best, stalled_steps)


def in_one_call(
    sim: SimulatorView, before: NDArray, requested: NDArray, applied: NDArray, stats: Any
) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_]]:
    """``hook_by_hook`` in one compiled call (the scenario must be ``one_call_serves``)."""
    s, sc, m = sim.state, sim.scenario, sim.metrics
    feasible, min_h = m.begin(stats)
    p = sc.params
    rh_on = sc.right_hand_on
    E, n = s.at_goal.shape
    out = (
        np.empty((E, n)),
        np.empty((E, n, sim.k), dtype=np.int64),
        np.empty((E, n), dtype=np.bool_),
        np.empty((E, n), dtype=np.bool_),
        np.empty((E, n)),
        np.empty(E, dtype=np.bool_),
        np.empty(E, dtype=np.bool_),
    )
    _in_one_call(
        np.ascontiguousarray(s.positions),
        np.ascontiguousarray(before),
        np.ascontiguousarray(s.goals),
        s.starts,
        s.reached,
        sim.k,
        float(p["goal_tolerance"]),
        rh_on,
        float(sc.rh_trigger) if rh_on else 0.0,
        float(p["rh_hold"]),
        sim.reward_weights,
        m.counts,
        m.min_distance,
        m.infeasible,
        m.sums,
        m.arrival,
        m.min_barrier,
        applied,
        requested,
        feasible,
        min_h,
        m.dt,
        m.collision_below,
        m.step_series,
        sim.max_steps,
        PROGRESS * sim.safety_radius,
        sim.progress.best,
        sim.progress.steps,
        *out,
    )
    m.end()
    s.nearest, s.neighbors, s.at_goal, s.rh_active, reward, terminated, truncated = out
    return reward, terminated, truncated
