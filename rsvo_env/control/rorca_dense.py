"""R-ORCA's compiled stage for envs of at most ``DENSE_MAX_AGENTS`` agents: each agent's
candidates are the others of its env within the cut, read in place, and its weights straight
from the env's weight matrix (E, N, N), which the simulation core keeps
(``rsvo_env.sim.weights``): no pair list, no neighbour lists, no weights computed again. The
velocities are bit for bit those of the grid stage (``rsvo_env.control.rorca_grid``): the same
candidates in the same order (those after the agent in its env, then those before, the order
of its pairs), the same arithmetic (``rsvo_env.control.rorca_agent``)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from rsvo_env.control.rorca_agent import (
    cap_scale,
    cap_wanted,
    goal_gap,
    plane,
    scratch,
    seen,
    shares,
    solve,
)
from rsvo_env.responsibility.svo import Weighting, named_weights, symmetric_envs, weight_matrix
from rsvo_env.util import threads

# agents a chunk of the parallel form
CHUNK = 64


def matrices(theta: NDArray, modes: Sequence[Weighting]) -> NDArray[np.float64]:
    """(E, N, N) each env's weight matrix from its scores ``theta`` (E, N) and weighting, the
    numbers ``pairs.weights_of`` gives its pairs."""
    if any(callable(m) for m in modes):
        return np.stack([weight_matrix(t, m) for t, m in zip(theta, modes, strict=True)])
    W = named_weights(np.ascontiguousarray(theta, dtype=np.float64), "asymmetric")
    W[symmetric_envs(modes)] = 0.5
    return W


@njit(cache=True)
def _caps(lo, hi, n, motion, held, tau, cut, pref):
    """Agents lo..hi's preferred velocities with the arrival cap into ``pref``
    (``rorca._capped``), their neighbours within ``cut`` scanned only where the cap can apply.
    Every pass is a function called once a block, its helpers given scalars: an array handed to
    an inlined helper costs two atomic reference counts, as much as an agent's arithmetic."""
    x, g, pref0, r = motion[0], motion[2], motion[3], motion[4]
    for a in range(lo, hi):
        ga, pa = (g[a, 0], g[a, 1]), (pref0[a, 0], pref0[a, 1])
        wanted, speed, dist = cap_wanted(pa, (x[a, 0], x[a, 1]), ga, held[a], tau)
        gap = np.inf
        if wanted:
            base = a - a % n
            for j in range(base, base + n):
                dx, dy = x[a, 0] - x[j, 0], x[a, 1] - x[j, 1]
                if j != a and np.sqrt(dx * dx + dy * dy) <= cut:
                    gap = min(gap, goal_gap(ga, (x[j, 0], x[j, 1]), r[a], r[j]))
        scale = cap_scale(wanted, speed, dist, tau, gap)
        pref[a, 0], pref[a, 1] = pa[0] * scale, pa[1] * scale


@njit(cache=True)
def _bound(d2s, count, keep, near):
    """(bound, last): the squared distance of the ``keep``-th nearest of ``d2s[:count]`` and
    its position (ties: the earlier is the nearer), by insertion into ``near`` (keep, 2)."""
    filled = 0
    for c in range(count):
        d2 = d2s[c]
        if filled == keep and d2 >= near[keep - 1, 0]:
            continue
        pos = min(filled, keep - 1)
        while pos > 0 and near[pos - 1, 0] > d2:
            near[pos, 0], near[pos, 1] = near[pos - 1, 0], near[pos - 1, 1]
            pos -= 1
        near[pos, 0], near[pos, 1] = d2, c
        filled = min(filled + 1, keep)
    return near[keep - 1, 0], near[keep - 1, 1]


@njit(cache=True)
def _agents(lo, hi, n, x, v, pref, r, W, tied, park, settings, out):
    """Agents lo..hi's R-ORCA velocities (before the speed clip) into ``out``, as the grid stage
    gives them: the half-planes of each one's K nearest candidates (ties: the earlier), solved
    within the speed disk with the sidestep. The candidates: the others of its env within the
    cut, those after it, then those before (the order of its pairs), tested without a branch
    (whether one is within the cut is a coin toss in a dense crowd; one not within it is written
    and then overwritten). ``W``: the weight matrices as (E * n, n)."""
    K, u_max, tau, dt, cut = settings
    rows, bisectors, near = scratch(n - 1, K)
    cand, d2s = np.empty(max(n - 1, 1), dtype=np.int64), np.empty(max(n - 1, 1))
    for a in range(lo, hi):
        base = a - a % n
        xa, ya = x[a, 0], x[a, 1]
        count = 0
        for t in range(1, n):
            j = a + t
            j = j - n if j >= base + n else j
            # the pair's distance whichever side computes it (x_a - x_j is x_j - x_a negated)
            dx, dy = xa - x[j, 0], ya - x[j, 1]
            d2 = dx * dx + dy * dy
            cand[count], d2s[count] = j, d2
            count += np.sqrt(d2) <= cut
        keep = count if K < 0 else min(K, count)
        bound, last = np.inf, count
        if keep < count:
            bound, last = _bound(d2s, count, keep, near)
        mine = (xa, ya, v[a, 0], v[a, 1])
        nrows = 0
        for c in range(count):
            if keep < count and (d2s[c] > bound or (d2s[c] == bound and c > last)):
                continue
            j = cand[c]
            first, second = min(a, j), max(a, j)
            w0, w1 = W[first, second - base], W[second, first - base]
            avoid, slack = shares(tied, park[first], park[second], w0, w1, a < j)
            vo = seen(park[a], park[j], pref[j, 0], pref[j, 1], v[j, 0], v[j, 1])
            rows[nrows, 0], rows[nrows, 1], rows[nrows, 2] = plane(
                mine, (x[j, 0], x[j, 1]), vo, r[a] + r[j], avoid, slack, 1.0 / tau, dt
            )
            nrows += 1
        out[a, 0], out[a, 1] = solve(pref[a, 0], pref[a, 1], rows, nrows, u_max, bisectors)


@njit(cache=True)
def _stage_serial(n, motion, W, tied, park, held, settings, pref, out):
    """R-ORCA for every agent of envs of ``n``: ``motion`` (x, v, goals, preferred, radii),
    flat (E * n, ...); ``settings`` (K, u_max, tau, dt, cut); the capped preferred velocities
    into ``pref``. Every cap before any solve: a solve reads its neighbours' capped
    velocities."""
    M = motion[0].shape[0]
    _caps(0, M, n, motion, held, settings[2], settings[4], pref)
    _agents(0, M, n, motion[0], motion[1], pref, motion[4], W, tied, park, settings, out)


@njit(cache=True, parallel=True)
def _stage_parallel(n, motion, W, tied, park, held, settings, pref, out):
    """:func:`_stage_serial` over chunks of agents in parallel."""
    x, v, r = motion[0], motion[1], motion[4]
    M = x.shape[0]
    blocks = (M + CHUNK - 1) // CHUNK
    for c in prange(blocks):
        _caps(c * CHUNK, min(M, (c + 1) * CHUNK), n, motion, held, settings[2], settings[4], pref)
    for c in prange(blocks):
        _agents(c * CHUNK, min(M, (c + 1) * CHUNK), n, x, v, pref, r, W, tied, park, settings,
                out)  # fmt: skip


def stage(
    n: int, motion: tuple, omega: NDArray, tied: bool, park: NDArray, held: NDArray,
    settings: tuple, pref: NDArray, out: NDArray,
) -> None:  # fmt: skip
    """R-ORCA's velocities into ``out`` (E * n, 2) for envs of ``n`` agents: ``motion`` (x, v,
    goals, preferred, radii), flat; ``omega`` (E, n, n) the weight matrices; ``park``,
    ``held`` (E * n,); ``settings`` (K, u_max, tau, dt, cut); the capped preferred velocities
    into ``pref``."""
    W = np.ascontiguousarray(omega, dtype=np.float64).reshape(-1, n)
    threads.launch(_stage_serial, _stage_parallel, len(pref), n, motion, W, tied, park, held,
                   settings, pref, out)  # fmt: skip
