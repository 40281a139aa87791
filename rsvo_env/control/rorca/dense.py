"""R-ORCA's compiled stage for envs of at most ``sizes.ALL_PAIRS_MAX_AGENTS`` agents: each agent's
candidates are the others of its env within the cut, read in place, and its weights straight
from the env's weight matrix (E, N, N), which the simulation core keeps
(``rsvo_env.sim.weights``): no pair list, no neighbour lists, no weights computed again. The
velocities are bit for bit those of the grid stage (``rsvo_env.control.rorca.grid``): the same
candidates in the same order (those after the agent in its env, then those before, the order
of its pairs), the same arithmetic (``rsvo_env.control.rorca.agent``)."""

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
    within,
)
from rsvo_env.util import threads
from rsvo_env.util.planar import clip2
from rsvo_env.util.scratch import borrow

# agents a chunk of the parallel form
CHUNK = 64


@njit(cache=True)
def _caps(lo, hi, n, motion, rules, tau, cut, pref, park):
    """Agents lo..hi's preferred velocities with the arrival cap into ``pref``
    (``rorca.arrival_capped``), their neighbours within ``cut`` scanned only where the cap can
    apply, and whether each counts as parked into ``park``: ``rules`` (parked, held, tied,
    reach, goal_held), who counts as parked by ``agent.counts_parked``.
    Every pass is a function called once a block, its helpers given scalars: an array handed to
    an inlined helper costs two atomic reference counts, as much as an agent's arithmetic."""
    x, g, pref0, r = motion[0], motion[2], motion[3], motion[4]
    parked, held, tied, reach, goal_held = rules
    cut2 = within(cut)
    for a in range(lo, hi):
        xa, ga, pa = (x[a, 0], x[a, 1]), (g[a, 0], g[a, 1]), (pref0[a, 0], pref0[a, 1])
        park[a] = counts_parked(tied, parked[a], xa, ga, r[a], goal_held[a], reach)
        wanted, speed, dist = cap_wanted(pa, xa, ga, held[a], tau)
        gap = np.inf
        if wanted:
            base = a - a % n
            for j in range(base, base + n):
                dx, dy = x[a, 0] - x[j, 0], x[a, 1] - x[j, 1]
                if j != a and dx * dx + dy * dy <= cut2:
                    gap = min(gap, goal_gap(ga, (x[j, 0], x[j, 1]), r[a], r[j]))
        scale = cap_scale(wanted, speed, dist, tau, gap)
        pref[a, 0], pref[a, 1] = pa[0] * scale, pa[1] * scale


@njit(cache=True)
def _agents(lo, hi, n, x, v, pref, r, W, tied, park, settings, space, out):
    """Agents lo..hi's R-ORCA velocities into ``out``, as the grid stage gives them: the
    half-planes of each one's K nearest candidates (ties: the earlier), solved within the speed
    disk with the sidestep, clipped to the speed limit. The candidates: the others of its env
    within the cut, those after it, then those before (the order of its pairs), tested without
    a branch (whether one is within the cut is a coin toss in a dense crowd; one not within it
    is written and then overwritten). ``W``: the weight matrices as (E * n, n); ``space`` the
    rows' and the solver's scratch (``agent.scratch``), borrowed (``util.scratch``):
    handed down the inlined solve, counted arrays would cost a quarter of the time."""
    K, u_max, tau, dt, cut = settings
    rows, bisectors = borrow(space[0]), borrow(space[1])
    width = max(n - 1, 1)
    cand, kept = np.empty(width, np.int64), np.empty(width, np.int64)
    # room for the distances to a multiple of 8 (one vector of them), the rest never nearer
    d2s = np.full(width + 7, np.inf)
    cut2 = within(cut)
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
            count += d2 <= cut2
        keep = count if K < 0 else min(K, count)
        # the K nearest, in candidate order: each one's rank (ties: the earlier is the nearer)
        # counted without a branch (a sort's comparisons mispredict, and cost more than the
        # count's K^2 sums), and the kept listed without one; the count over whole vectors of
        # 8 (a remainder loop costs as much as the vectors before it)
        padded = (count + 7) // 8 * 8
        for m in range(count, padded):
            d2s[m] = np.inf
        nrows = 0
        for c in range(count):
            d2, rank = d2s[c], 0
            for m in range(padded):
                rank += (d2s[m] < d2) | ((d2s[m] == d2) & (m < c))
            kept[nrows] = cand[c]
            nrows += rank < keep
        mine = (xa, ya, v[a, 0], v[a, 1])
        for k in range(nrows):
            j = kept[k]
            first, second = min(a, j), max(a, j)
            w0, w1 = W[first, second - base], W[second, first - base]
            avoid, slack = shares(tied, park[first], park[second], w0, w1, a < j)
            vo = seen(park[a], park[j], pref[j, 0], pref[j, 1], v[j, 0], v[j, 1])
            rows[k, 0], rows[k, 1], rows[k, 2] = plane(
                mine, (x[j, 0], x[j, 1]), vo, r[a] + r[j], avoid, slack, 1.0 / tau, dt
            )
        u = solve(pref[a, 0], pref[a, 1], rows, nrows, u_max, bisectors)
        # a point on the disk's edge lies on it only to rounding: the speed limit holds exactly
        out[a, 0], out[a, 1] = clip2(u[0], u[1], u_max)


@njit(cache=True)
def _stage_serial(n, motion, W, rules, settings, pref, park, out):
    """R-ORCA for every agent of envs of ``n`` (``stage``); the capped preferred velocities
    into ``pref``, who counts as parked into ``park``. Every cap before any solve: a solve reads
    its neighbours' capped velocities."""
    M = motion[0].shape[0]
    _caps(0, M, n, motion, rules, settings[2], settings[4], pref, park)
    space = scratch(n - 1, settings[0])
    _agents(0, M, n, motion[0], motion[1], pref, motion[4], W, rules[2], park, settings, space, out)


@njit(cache=True, parallel=True)
def _stage_parallel(n, motion, W, rules, settings, pref, park, out):
    """``_stage_serial`` over chunks of agents in parallel."""
    x, v, r = motion[0], motion[1], motion[4]
    M = x.shape[0]
    blocks = (M + CHUNK - 1) // CHUNK
    for c in prange(blocks):
        _caps(
            c * CHUNK,
            min(M, (c + 1) * CHUNK),
            n,
            motion,
            rules,
            settings[2],
            settings[4],
            pref,
            park,
        )
    for c in prange(blocks):
        space = scratch(n - 1, settings[0])
        _agents(
            c * CHUNK,
            min(M, (c + 1) * CHUNK),
            n,
            x,
            v,
            pref,
            r,
            W,
            rules[2],
            park,
            settings,
            space,
            out,
        )


def stage(
    n: int, motion: tuple, omega: NDArray, rules: tuple, settings: tuple
) -> NDArray[np.float64]:
    """R-ORCA's velocities (E * n, 2), clipped to the speed limit, for envs of ``n`` agents:
    ``motion`` (x, v, goals, preferred, radii), flat (E * n, ...); ``omega`` (E, n, n) the
    weight matrices; ``rules`` (parked, held, tied, reach, goal_held): the agents parked and
    held (E * n,), whether the parked rule is on, the goal rule's reach and the agents held long
    enough for it (E * n,); ``settings`` (K, u_max,
    tau, dt, cut), K < 0 for every neighbour within the cut."""
    W = np.ascontiguousarray(omega, dtype=np.float64).reshape(-1, n)
    M = motion[0].shape[0]
    pref, park, out = np.empty((M, 2)), np.empty(M, np.bool_), np.empty((M, 2))
    threads.launch(
        _stage_serial, _stage_parallel, M, n, motion, W, rules, settings, pref, park, out
    )
    return out
