"""R-ORCA's compiled stage for envs of more than ``sizes.ALL_PAIRS_MAX_AGENTS`` agents, ORCA's way,
in one call: each agent scans a grid of its env for its K nearest neighbours within the cut (where
ORCA queries a k-d tree), with no pair list and no neighbour lists, and a weight is computed only
for a pair kept. The agents are visited in cell order, reading copies of their data laid out in that
order, so a neighbourhood is a few runs of consecutive memory (a crowd of 10,000 in index order
misses the cache at nearly every neighbour).

The velocities are bit for bit those R-ORCA assembled pair by pair gives
(``tests/control/test_rorca.py``) and the dense stage's (``rsvo_env.control.rorca.dense``): the same
candidates (within the cut, ``d^2 <= cut^2`` as the grid pair search decides it), the same K nearest
with ties broken by the order of the agent's pairs (its neighbours after it, then those before it),
the rows stacked in that order, the same arithmetic (``rsvo_env.control.rorca.agent``) and the same
weights (the libm cosine numpy's takes too, of the same shares; or the env's matrix, read)."""

from __future__ import annotations

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from rsvo_env.control.rorca.agent import (
    cap_scale,
    cap_wanted,
    counts_parked,
    goal_gap,
    plane,
    scratch,
    seen,
    shares,
    solve,
)
from rsvo_env.responsibility.svo import share_of
from rsvo_env.util import threads
from rsvo_env.util.grid import build_cells, cell_span
from rsvo_env.util.planar import clip2
from rsvo_env.util.scratch import borrow

# the list width a call with every neighbour (K < 0) tries first; a crowd denser than that is
# scanned again with its widest count
FIRST_WIDTH = 16
# agents a chunk of the parallel form
CHUNK = 64


@njit(cache=True)
def _index(x, n, cut):
    """Each env's grid (``util.grid.build_cells``, cells of side ``cut / 2``: a scan covers about
    twice the cut's disk, where cells of side ``cut`` cover three times it): ``perm`` (M,) the
    agents in cell order env by env, ``start`` (E, cells + 1) each env's cell offsets within
    its n, ``geometry`` (E, 5) origin, side and counts of its cells."""
    M = x.shape[0]
    E = M // n
    perm = np.empty(M, dtype=np.int64)
    start = np.zeros((E, 4 * n + 65), dtype=np.int64)
    geometry = np.empty((E, 5))
    for e in range(E):
        lo0, lo1, c, nx, ny, st, order = build_cells(x[e * n : (e + 1) * n], 0.5 * cut)
        perm[e * n : (e + 1) * n] = order + e * n
        start[e, : nx * ny + 1] = st
        geometry[e, 0], geometry[e, 1], geometry[e, 2] = lo0, lo1, c
        geometry[e, 3], geometry[e, 4] = nx, ny
    return perm, start, geometry


@njit(cache=True)
def _gather(perm, motion, theta, parked, held, tied, reach, goal_held):
    """The agents' data in cell order (copies), the order both passes visit and read them in:
    (x, v, goals, preferred, radii, theta, parked, held), who counts as parked by
    ``agent.counts_parked``."""
    x, v, g, pref0, r = motion
    M = perm.shape[0]
    xs, vs, gs, ps = np.empty((M, 2)), np.empty((M, 2)), np.empty((M, 2)), np.empty((M, 2))
    rs, ths = np.empty(M), np.empty(M)
    parks, holds = np.empty(M, np.bool_), np.empty(M, np.bool_)
    for s in range(M):
        a = perm[s]
        xs[s, 0], xs[s, 1], vs[s, 0], vs[s, 1] = x[a, 0], x[a, 1], v[a, 0], v[a, 1]
        gs[s, 0], gs[s, 1], ps[s, 0], ps[s, 1] = g[a, 0], g[a, 1], pref0[a, 0], pref0[a, 1]
        rs[s], ths[s], holds[s] = r[a], theta[a], held[a]
        parks[s] = counts_parked(
            tied, parked[a], (x[a, 0], x[a, 1]), (g[a, 0], g[a, 1]), r[a], goal_held[a], reach
        )
    return xs, vs, gs, ps, rs, ths, parks, holds


@njit(cache=True)
def _list_block(lo, hi, n, data, index, settings, keep, lists, within):
    """Agents lo..hi (cell order): each one's neighbours within the cut (their number into
    ``within``), its ``keep`` nearest (ties: the earlier of its pairs) into ``nbr[s]`` in the
    order of its pairs (the order its rows stack in) and their number into ``count[s]``
    (``lists``: pref, nbr, count), and its capped preferred velocity into ``pref[s]`` (the gap
    from its goal to every neighbour's body).

    The scan lists the agents of the cells within reach that lie within the cut without a
    branch (about half of those scanned lie beyond it, a coin toss a branch mispredicts), then
    keeps the nearest by replacing the farthest kept (a scan in space order replaces few); the
    kept are ordered by their rank among the keys, counted without a branch. No helper is
    handed an array: an array handed to a function costs two atomic reference counts
    (``util.scratch``)."""
    cut, tau = settings[4], settings[2]
    xs, gs, ps, rs, holds = data[0], data[2], data[3], data[4], data[7]
    perm, start, geometry = index
    pref, nbr, count = lists
    M = perm.shape[0]
    width = nbr.shape[1]
    d2s, keys, kept = np.empty(width), np.empty(width, np.int64), np.empty(width, np.int64)
    # a scan reads only its own env's agents: at most n of them within the cut
    near, near_d2 = np.empty(n, np.int64), np.empty(n)
    cut2 = cut * cut
    # the cells a hair beyond the cut too: |dx| may round above the cut where d^2 is within it
    reach = cut * (1.0 + 1e-12)
    for s in range(lo, hi):
        e = s // n
        base = e * n
        lo0, lo1, c = geometry[e, 0], geometry[e, 1], geometry[e, 2]
        nx, ny = int(geometry[e, 3]), int(geometry[e, 4])
        xs_s = (xs[s, 0], xs[s, 1])
        a0, b0 = cell_span(xs_s[0], reach, lo0, c, nx)
        a1, b1 = cell_span(xs_s[1], reach, lo1, c, ny)
        w = 0
        for gx in range(a0, b0 + 1):
            # cells a1..b1 of a column are consecutive: their agents are one run
            for t in range(start[e, gx * ny + a1], start[e, gx * ny + b1 + 1]):
                j = base + t
                dx, dy = xs_s[0] - xs[j, 0], xs_s[1] - xs[j, 1]
                d2 = dx * dx + dy * dy
                near[w], near_d2[w] = j, d2
                w += (d2 <= cut2) & (j != s)
        within[s] = w
        gs_s, ps_s = (gs[s, 0], gs[s, 1]), (ps[s, 0], ps[s, 1])
        wanted, speed, dist = cap_wanted(ps_s, xs_s, gs_s, holds[s], tau)
        gap = np.inf
        if wanted:
            for k in range(w):
                j = near[k]
                gap = min(gap, goal_gap(gs_s, (xs[j, 0], xs[j, 1]), rs[s], rs[j]))
        scale = cap_scale(wanted, speed, dist, tau, gap)
        pref[s, 0], pref[s, 1] = ps_s[0] * scale, ps_s[1] * scale
        me = perm[s]
        filled, worst = 0, 0
        for k in range(w):
            j, d2 = near[k], near_d2[k]
            # the agent's pairs: first those with the agents after it, then before it
            other = perm[j]
            key = other + M * (other < me)
            changed = False
            if filled < keep:
                d2s[filled], keys[filled], kept[filled] = d2, key, j
                filled += 1
                changed = filled == keep
            elif keep > 0 and (d2 < d2s[worst] or (d2 == d2s[worst] and key < keys[worst])):
                d2s[worst], keys[worst], kept[worst] = d2, key, j
                changed = True
            if changed:  # the farthest of the kept (by distance, then key: the later pair)
                worst = 0
                for m in range(1, keep):
                    if d2s[m] > d2s[worst] or (d2s[m] == d2s[worst] and keys[m] > keys[worst]):
                        worst = m
        for k in range(filled):
            rank = 0
            for m in range(filled):
                rank += keys[m] < keys[k]
            nbr[s, rank] = kept[k]
        count[s] = filled


@njit(cache=True, inline="always")
def _weigh_block(lo, hi, n, perm, ths, lists, W, weight):
    """Agents lo..hi's kept pairs' weights into ``weight`` (M, K, 2), the first agent's (the
    lower index) and the second's: the matrices ``W`` (E * n, n)'s entries, or without them
    (``W`` empty) ``cos(pi theta_first / (theta_first + theta_second))`` into
    ``weight[..., 0]``, turned into weights where they are read (``_solve_block``). The
    cosine is libm's, as numpy's (``responsibility.pair_weights.scored_pairs``), in a loop of
    its own: in the solve's it costs four times as much."""
    nbr, count = lists[1], lists[2]
    matrix = W.shape[0] > 0
    for s in range(lo, hi):
        for k in range(count[s]):
            j = nbr[s, k]
            first, second = min(perm[s], perm[j]), max(perm[s], perm[j])
            if matrix:
                weight[s, k, 0], weight[s, k, 1] = W[first, second % n], W[second, first % n]
            elif perm[s] < perm[j]:
                weight[s, k, 0] = share_of(ths[s], ths[j]) * np.pi
            else:
                weight[s, k, 0] = share_of(ths[j], ths[s]) * np.pi
        if not matrix:
            for k in range(count[s]):
                weight[s, k, 0] = np.cos(weight[s, k, 0])


@njit(cache=True)
def _solve_block(lo, hi, n, perm, data, lists, weighting, tied, settings, space, out):
    """Agents lo..hi (cell order): the half-planes of their kept neighbours (``lists``: pref,
    nbr, count), solved within the speed disk with the sidestep (``agent.solve``), into
    ``out`` (M, 2) at their own indices, clipped to the speed limit. ``weighting`` (weight,
    symmetric, cosines): the weights ``weight`` (M, K, 2), or with ``cosines``
    ``(1 + weight[..., 0]) / 2`` and 1 minus that (1/2 in the ``symmetric`` (E,) envs), as
    ``responsibility.pair_weights.scored_pairs`` gives them.
    ``space``: the rows' and the solver's scratch, borrowed (``util.scratch``)."""
    xs, vs, gs, ps, rs, ths, parks, holds = data
    pref, nbr, count = lists
    weight, symmetric, cosines = weighting
    K, u_max, tau, dt, cut = settings
    rows, bisectors = borrow(space[0]), borrow(space[1])
    inv_tau = 1.0 / tau
    for s in range(lo, hi):
        # once an agent: an integer division costs as much as a row's arithmetic
        half = cosines and symmetric[s // n]
        mine = (xs[s, 0], xs[s, 1], vs[s, 0], vs[s, 1])
        for k in range(count[s]):
            j = nbr[s, k]
            me_first = perm[s] < perm[j]
            first, second = (s, j) if me_first else (j, s)
            if cosines:
                w0 = 0.5 if half else 0.5 * (1.0 + weight[s, k, 0])
                w1 = 1.0 - w0
            else:
                w0, w1 = weight[s, k, 0], weight[s, k, 1]
            avoid, slack = shares(tied, parks[first], parks[second], w0, w1, me_first)
            vo = seen(parks[s], parks[j], pref[j, 0], pref[j, 1], vs[j, 0], vs[j, 1])
            # a unit normal by construction (a leg's or the cutoff circle's direction): stored
            # as it is, where normalising it again would cost as much as the QP
            rows[k, 0], rows[k, 1], rows[k, 2] = plane(
                mine, (xs[j, 0], xs[j, 1]), vo, rs[s] + rs[j], avoid, slack, inv_tau, dt
            )
        u = solve(pref[s, 0], pref[s, 1], rows, count[s], u_max, bisectors)
        # a point on the disk's edge lies on it only to rounding: the speed limit holds exactly
        me = perm[s]
        out[me, 0], out[me, 1] = clip2(u[0], u[1], u_max)


@njit(cache=True, inline="always")
def _lists(M, keep):
    """(pref, nbr, count) for M agents with room for ``keep`` neighbours each, and ``within``."""
    width = max(keep, 1)
    lists = np.empty((M, 2)), np.empty((M, width), np.int64), np.empty(M, np.int64)
    return lists, np.empty(M, np.int64)


@njit(cache=True, parallel=True)
def _stage(n, motion, theta, rules, W, symmetric, settings, out):
    """``_passes`` with its chunks of agents in parallel."""
    _passes(n, motion, theta, rules, W, symmetric, settings, out)


@njit(cache=True)
def stage_serial(n, motion, theta, rules, W, symmetric, settings, out):
    """``_passes`` on the calling thread, its chunks one after the other: on one thread
    the faster form (a parallel region costs its launch even on one thread)."""
    _passes(n, motion, theta, rules, W, symmetric, settings, out)


@njit(cache=True, inline="always")
def _passes(n, motion, theta, rules, W, symmetric, settings, out):
    """R-ORCA for every agent of envs of ``n`` (``stage``), pass after pass, each over chunks
    of agents: the grid and the data in cell order, each agent's K nearest and capped
    preferred velocity, their pairs' weights, the solves (each clipped to the speed limit)."""
    K = settings[0]
    M = motion[0].shape[0]
    blocks = (M + CHUNK - 1) // CHUNK
    index = _index(motion[0], n, settings[4])
    data = _gather(index[0], motion, theta, *rules)
    keep = FIRST_WIDTH if K < 0 else K
    lists, within = _lists(M, keep)
    for c in prange(blocks):
        _list_block(
            c * CHUNK, min(M, (c + 1) * CHUNK), n, data, index, settings, keep, lists, within
        )
    if K < 0 and M > 0 and within.max() > keep:
        keep = within.max()
        lists, within = _lists(M, keep)
        for c in prange(blocks):
            _list_block(
                c * CHUNK, min(M, (c + 1) * CHUNK), n, data, index, settings, keep, lists, within
            )
    weight = np.empty((M, lists[1].shape[1], 2))
    for c in prange(blocks):
        _weigh_block(c * CHUNK, min(M, (c + 1) * CHUNK), n, index[0], data[5], lists, W, weight)
    weighting = (weight, symmetric, W.shape[0] == 0)
    for c in prange(blocks):
        space = scratch(lists[1].shape[1], lists[1].shape[1])
        _solve_block(
            c * CHUNK,
            min(M, (c + 1) * CHUNK),
            n,
            index[0],
            data,
            lists,
            weighting,
            rules[2],
            settings,
            space,
            out,
        )


def stage(
    n: int,
    motion: tuple,
    theta: NDArray,
    symmetric: NDArray[np.bool_],
    omega: NDArray | None,
    rules: tuple,
    settings: tuple,
) -> NDArray[np.float64]:
    """R-ORCA's velocities (E * n, 2), clipped to the speed limit, for envs of ``n`` agents:
    ``motion`` (x, v, goals, preferred, radii), flat (E * n, ...); the weights from the matrices
    ``omega`` (E, n, n) where given, else from the scores ``theta`` (E, n), 1/2 in the
    ``symmetric`` (E,) envs; ``rules`` (parked, held, tied, reach, goal_held): the agents parked
    and held (E * n,), whether the parked rule is on, the goal rule's reach and the agents held
    long enough for it (E * n,); ``settings`` (K, u_max,
    tau, dt, cut), K < 0 for every neighbour within the cut."""
    M = motion[0].shape[0]
    if omega is None:
        W = np.zeros((0, n))
    else:
        W = np.ascontiguousarray(omega, dtype=np.float64).reshape(M, n)
    th = np.ascontiguousarray(theta, dtype=np.float64).reshape(M)
    K, u_max, tau, dt, cut = settings
    out = np.empty((M, 2))
    args = (
        n,
        motion,
        th,
        rules,
        W,
        np.ascontiguousarray(symmetric, dtype=np.bool_),
        (int(K), float(u_max), float(tau), float(dt), float(cut)),
        out,
    )
    if threads.parallel(M):
        threads.launch(stage_serial, _stage, M, *args)
    else:  # a parallel region costs its launch even on one thread
        stage_serial(*args)
    return out
