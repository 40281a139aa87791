"""R-ORCA: ORCA's reciprocal half-planes with the R-SVO weights in place of its fixed one-half
split, as an active nominal controller for single integrators (``docs/liveness.md``).

ORCA (van den Berg et al., 2011) gives agent i, for each neighbour j within ``neighbor_dist``,
the smallest change ``u`` of the relative velocity that leaves the truncated velocity obstacle
(horizon ``tau``), and asks i to take half of it: the half-plane of velocities v with
``(v - (v_i + u / 2)) . n >= 0`` (``n`` the outward normal). Here agent i takes the share
``1 - omega_ij`` of ``u`` where it is avoidance (the relative velocity inside the obstacle) and
``omega_ij`` where it is slack (outside, ``u`` the room left to close), eq. ``rorca``: the egoist
(larger omega) does less of the avoidance and gets more of the slack, as the filter's rows give
it, and ``omega = 1/2`` is ORCA. Unlike a filter's rows these are *active*: an agent parked on
its goal whose velocity obstacle holds 0 must step aside, which is what makes crowds finish.
The velocity is the one closest to the preferred velocity within the half-planes and the speed
disk, by ORCA's own linear programs (``rsvo_env.qp.disk``); where they leave no room, the
velocity of the disk whose largest violation is least (ORCA's third). The R-CBF
filter on top keeps the guarantee whatever this controller proposes. Envs of at most
``DENSE_MAX_AGENTS`` agents run :mod:`rsvo_env.control.rorca_dense`'s stage (the env's agents
read in place, the weights from its matrix); larger ones this module's, over the pairs of the
grid search.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from rsvo_env.control import rorca_dense

# ARRIVE, HOLD_SECONDS and SIDESTEP are the rules' constants, read through this module
from rsvo_env.control.rorca_agent import (  # noqa: F401
    ARRIVE,
    HOLD_SECONDS,
    SIDESTEP,
    cap_wanted,
    cap_write,
    goal_gap,
    insert_nearest,
    plane,
    scratch,
    shares,
    solve,
)
from rsvo_env.geometry import pairs
from rsvo_env.responsibility.svo import Weighting
from rsvo_env.util import sizes, threads
from rsvo_env.util.planar import clip_norm

# an agent held within this many of its radii of its goal (1: the goal under its own body) yields
# as if parked (goal_blocked); 2 to 4 measured, quicker crowds of 1,000 but the circular swap's
# egoists no longer first at every size (docs/liveness.md)
GOAL_REACH = 1.0


@njit(cache=True)
def _half_planes(x, v, radii, I, J, share, tau, dt, parked, seen):
    """Both directed half-planes of each pair (I, J): rows ``A . v <= b`` for agent I (first
    P) and agent J (last P), ``share`` (P, 2) each side's part of the avoidance (summing to 1;
    of the slack each side takes the other's share). An agent ``parked`` (M,) reads a neighbour
    en route at the velocity ``seen`` (M, 2) instead of its current one."""
    P = I.shape[0]
    A = np.empty((2 * P, 2))
    b = np.empty(2 * P)
    for p in range(P):
        for side in range(2):
            me, other = (I[p], J[p]) if side == 0 else (J[p], I[p])
            vo = seen[other] if parked[me] and not parked[other] else v[other]
            row = plane(x, v, radii, me, other, vo, share[p, side], share[p, 1 - side],
                        1.0 / tau, dt)  # fmt: skip
            k = p + side * P
            A[k, 0], A[k, 1], b[k] = row
    return A, b


@njit(cache=True)
def _neighbor_lists(I, J, x, cut, M):
    """Each agent's candidate neighbours (CSR ``offsets`` (M + 1,), ``other``, ``pair``,
    ``side``) among the pairs (I, J) within ``cut`` of each other: the pairs where it is first,
    in pair order, then those where it is second, the order in which an agent's rows stack.
    Branch-free: whether a pair is near is a coin toss in a dense crowd, and a mispredicted
    branch a pair cost more than the rest (a pair not near writes to a spare last slot)."""
    P = I.shape[0]
    near = np.empty(P, dtype=np.int64)
    offsets = np.zeros(M + 1, dtype=np.int64)
    for p in range(P):
        dx, dy = x[I[p], 0] - x[J[p], 0], x[I[p], 1] - x[J[p], 1]
        near[p] = np.sqrt(dx * dx + dy * dy) <= cut
        offsets[I[p] + 1] += near[p]
        offsets[J[p] + 1] += near[p]
    for a in range(M):
        offsets[a + 1] += offsets[a]
    total = offsets[M]
    fill = offsets[:-1].copy()
    other = np.empty(total + 1, dtype=np.int64)
    pair = np.empty(total + 1, dtype=np.int64)
    side = np.empty(total + 1, dtype=np.int8)
    for s in range(2):
        for p in range(P):
            me, them = (I[p], J[p]) if s == 0 else (J[p], I[p])
            k = near[p] * fill[me] + (1 - near[p]) * total
            other[k], pair[k], side[k] = them, p, s
            fill[me] += near[p]
    return offsets, other[:total], pair[:total], side[:total]


@njit(cache=True, inline="always")
def _capped(a, x, g, pref, r, offsets, other, tau, held, out):
    """Agent a's preferred velocity with the arrival cap (:func:`arrival_capped`) into out[a]."""
    wanted, speed, dist = cap_wanted(a, x, g, pref, tau, held)
    gap = np.inf
    if wanted:
        for k in range(offsets[a], offsets[a + 1]):
            gap = min(gap, goal_gap(a, other[k], x, g, r))
    cap_write(a, pref, wanted, speed, dist, tau, gap, out)


@njit(cache=True, inline="always")
def _agent(a, x, v, pref, r, lists, w, tied, park, settings, rows, near, out):
    """Agent a's R-ORCA velocity (before the speed clip) into out[a]: the half-planes of its
    ``K`` nearest candidates (ties: the earlier in its list), solved within the speed disk
    with the sidestep (:func:`rorca_agent.solve`).
    ``lists``: :func:`_neighbor_lists`; ``settings``: (K, u_max, tau, dt); ``near``: scratch
    (widest list, 3)."""
    offsets, other, pair, side = lists
    K, u_max, tau, dt = settings
    inv_tau = 1.0 / tau
    start, stop = offsets[a], offsets[a + 1]
    count = stop - start
    keep = count if K < 0 else min(K, count)
    bound, last = np.inf, stop
    if keep < count:
        # the K nearest (K is ORCA's 10); each squared distance kept in near[:, 2] for the
        # pass below
        filled = 0
        for k in range(start, stop):
            j = other[k]
            dx, dy = x[a, 0] - x[j, 0], x[a, 1] - x[j, 1]
            d2 = dx * dx + dy * dy
            near[k - start, 2] = d2
            filled = insert_nearest(near, filled, keep, d2, k)
        bound, last = near[keep - 1, 0], near[keep - 1, 1]
    nrows = 0
    for k in range(start, stop):
        if keep < count:
            d2 = near[k - start, 2]
            if d2 > bound or (d2 == bound and k > last):
                continue
        j = other[k]
        p = pair[k]
        first, second = (a, j) if side[k] == 0 else (j, a)
        avoid, slack = shares(tied, park, first, second, w[p, 0], w[p, 1], side[k] == 0)
        vo = pref[j] if park[a] and not park[j] else v[j]
        # a unit normal by construction (a leg's or the cutoff circle's direction): stored as
        # it is, where normalising it again would cost as much as the QP
        rows[nrows, 0], rows[nrows, 1], rows[nrows, 2] = plane(
            x, v, r, a, j, vo, avoid, slack, inv_tau, dt
        )
        nrows += 1
    solve(pref[a, 0], pref[a, 1], rows, nrows, u_max, out[a])


@njit(cache=True)
def _widest_list(offsets):
    widest = 0
    for a in range(offsets.shape[0] - 1):
        widest = max(widest, offsets[a + 1] - offsets[a])
    return widest


@njit(cache=True)
def _stage_serial(motion, lists, w, tied, park, held, settings, pref, out):
    """R-ORCA for every agent: ``motion`` (x, v, goals, preferred, radii), ``lists`` and
    ``settings`` as :func:`_agent` reads them; the capped preferred velocities into ``pref``."""
    x, v, g, pref0, r = motion
    offsets, other = lists[0], lists[1]
    K, tau = settings[0], settings[2]
    M = x.shape[0]
    for a in range(M):
        _capped(a, x, g, pref0, r, offsets, other, tau, held, pref)
    width = _widest_list(offsets)
    rows, near = scratch(width, K)
    for a in range(M):
        _agent(a, x, v, pref, r, lists, w, tied, park, settings, rows, near, out)


@njit(cache=True, parallel=True)
def _stage_parallel(motion, lists, w, tied, park, held, settings, pref, out):
    """:func:`_stage_serial` over chunks of agents in parallel."""
    x, v, g, pref0, r = motion
    offsets, other = lists[0], lists[1]
    K, tau = settings[0], settings[2]
    M = x.shape[0]
    chunk = 64
    blocks = (M + chunk - 1) // chunk
    for c in prange(blocks):
        for a in range(c * chunk, min(M, (c + 1) * chunk)):
            _capped(a, x, g, pref0, r, offsets, other, tau, held, pref)
    width = _widest_list(offsets)
    for c in prange(blocks):
        rows, near = scratch(width, K)
        for a in range(c * chunk, min(M, (c + 1) * chunk)):
            _agent(a, x, v, pref, r, lists, w, tied, park, settings, rows, near, out)


def arrival_capped(
    preferred: NDArray, positions: NDArray, goals: NDArray, radii: NDArray, tau: float,
    I: NDArray[np.int64], J: NDArray[np.int64], held: NDArray[np.bool_] | None = None,
) -> NDArray[np.float64]:  # fmt: skip
    """``preferred`` (M, 2) scaled down to speed at most ``ARRIVE |goal - x| / tau`` where the
    look-ahead ``|preferred| tau`` passes the goal by more than the gap between the goal and a
    neighbour's body (pairs I, J; flat (M, 2) positions and goals, radii (M,)); with ``held``
    (M,), only there."""
    M = len(positions)
    f = lambda a: np.ascontiguousarray(a, dtype=np.float64)  # noqa: E731
    offsets, other, _, _ = _neighbor_lists(I, J, f(positions), np.inf, M)
    hold = np.ones(M, dtype=np.bool_) if held is None else np.ascontiguousarray(held)
    out = np.empty((M, 2))
    _cap_all(f(positions), f(goals), f(preferred), f(radii), offsets, other, float(tau), hold, out)
    return out


@njit(cache=True)
def _cap_all(x, g, pref, r, offsets, other, tau, held, out):
    for a in range(x.shape[0]):
        _capped(a, x, g, pref, r, offsets, other, tau, held, out)


def goal_blocked(
    positions: NDArray, goals: NDArray, radii: NDArray, held: NDArray[np.bool_]
) -> NDArray[np.bool_]:
    """(...,) the agents ``held`` short of a goal within ``GOAL_REACH`` of their own radii
    (``radii``; at 1, a goal under their own bodies), which R-ORCA treats as parked. A
    neighbour's body blocks such a goal, and an agent pressing for it pins that neighbour, which
    may be the very agent that must pass to free the goal (the crowd of 100 at its defaults,
    seed 3: an egoist 0.15 m short of its goal pinned an altruist between two parked agents for
    20,000 steps). Parked, it yields, the neighbour passes, and it comes back
    (``docs/liveness.md``)."""
    d = goals - positions
    reach = GOAL_REACH * radii
    return held & (np.sqrt(d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1]) <= reach)


class Rules(NamedTuple):
    """The state R-ORCA reads beyond the crowd's motion and scores: its rules' ``parked``
    (E, N) agents at their goals, ``goals`` (E, N, 2), ``held`` (E, N) agents held short of
    them; and ``omega`` (E, N, N), the weight matrices of the scores where the caller keeps them
    (the simulation core does, ``State.omega``), read rather than computed again."""

    parked: NDArray | None = None
    goals: NDArray | None = None
    held: NDArray | None = None
    omega: NDArray | None = None


def rorca_velocities(
    positions: NDArray,
    velocities: NDArray,
    preferred: NDArray,
    radii: NDArray,
    theta: NDArray,
    modes: list[Weighting],
    u_max: float,
    dt: float,
    tau: float = 2.0,
    neighbor_dist: float | None = None,
    max_neighbors: int | None = 10,
    rules: Rules | None = None,
) -> NDArray[np.float64]:
    """Eq. ``rorca``: each agent's velocity (E, N, 2) closest to ``preferred`` within its R-ORCA
    half-planes against the nearest ``max_neighbors`` (None: all) of the neighbours within
    ``neighbor_dist`` (default ``5 (r_i + r_j)`` of the largest pair), and the speed limit
    ``u_max`` (ORCA's defaults: 10 neighbours, 5 pair distances, horizon 2 s). ``radii``
    (E, N) or (N,); the weights come from the scores ``theta`` (E, N) and each env's weighting
    ``modes`` (``"symmetric"``: ORCA); ``parked`` (E, N): agents at their goals, which take all
    of the avoidance and none of the slack from agents en route, read at their preferred
    velocities, and so do the agents held short of goals under their own bodies
    (:func:`goal_blocked`); ``goals`` (E, N, 2): near its goal, where its look-ahead reaches a
    neighbour, an agent's preferred speed is capped (:func:`arrival_capped`), only the agents
    ``held`` (E, N) if given; these three are ``rules`` (:class:`Rules`, None: none of them),
    and so are the weight matrices ``omega`` (E, N, N) of ``theta`` and ``modes`` where the caller
    keeps them (read, not computed again)."""
    parked, goals, held, omega = (None, None, None, None) if rules is None else rules
    E, n = positions.shape[:2]
    M = E * n
    radii = np.broadcast_to(radii, (E, n))
    if neighbor_dist is None:
        neighbor_dist = 10.0 * float(radii.max())
    flat = lambda a: np.ascontiguousarray(a, dtype=np.float64).reshape(M, -1)  # noqa: E731
    x, v, pref0 = flat(positions), flat(velocities), flat(preferred)
    r = flat(radii).reshape(M)
    # the arrival cap applies where goals are given (to the agents held, if given)
    g = x if goals is None else flat(goals)
    if goals is None:
        hold = np.zeros(M, np.bool_)
    else:
        hold = np.ones(M, np.bool_) if held is None else np.ascontiguousarray(held).reshape(M)
    park = np.zeros(M, np.bool_)
    if parked is not None:
        park = np.ascontiguousarray(parked).reshape(M) | goal_blocked(x, g, r, hold)
    K = -1 if max_neighbors is None else int(max_neighbors)
    pref, out = np.empty((M, 2)), np.empty((M, 2))
    motion, tied = (x, v, g, pref0, r), parked is not None
    if n <= sizes.DENSE_MAX_AGENTS:  # every other agent of the env within neighbor_dist
        W = rorca_dense.matrices(theta, modes) if omega is None else omega
        settings = (K, float(u_max), float(tau), float(dt), float(neighbor_dist))
        rorca_dense.stage(n, motion, W, tied, park, hold, settings, pref, out)
    else:
        I, J = pairs.candidate_pairs(positions, neighbor_dist)
        if omega is None:
            w = np.ascontiguousarray(pairs.weights_of(theta, modes, I, J))
        else:  # the same numbers, gathered
            w = pairs.omega_pairs(np.ascontiguousarray(omega, dtype=np.float64).reshape(M, n),
                                  I, J, n)  # fmt: skip
        lists = _neighbor_lists(I, J, x, np.inf, M)
        settings = (K, float(u_max), float(tau), float(dt))
        threads.launch(_stage_serial, _stage_parallel, M, motion, lists, w, tied, park, hold,
                       settings, pref, out)  # fmt: skip
    # a point on the disk's edge lies on it only to rounding: the speed limit holds exactly
    return clip_norm(out, u_max).reshape(E, n, 2)
