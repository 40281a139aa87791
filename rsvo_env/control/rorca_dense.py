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
    cap_wanted,
    cap_write,
    goal_gap,
    insert_nearest,
    plane,
    scratch,
    shares,
    solve,
)
from rsvo_env.responsibility.svo import Weighting, named_weights, symmetric_envs, weight_matrix
from rsvo_env.util import threads


def matrices(theta: NDArray, modes: Sequence[Weighting]) -> NDArray[np.float64]:
    """(E, N, N) each env's weight matrix from its scores ``theta`` (E, N) and weighting, the
    numbers ``pairs.weights_of`` gives its pairs."""
    if any(callable(m) for m in modes):
        return np.stack([weight_matrix(t, m) for t, m in zip(theta, modes, strict=True)])
    W = named_weights(np.ascontiguousarray(theta, dtype=np.float64), "asymmetric")
    W[symmetric_envs(modes)] = 0.5
    return W


@njit(cache=True, inline="always")
def _candidates(a, n, x, cut, cand, d2s):
    """Agent a's neighbours within ``cut`` into ``cand`` (their squared distances from a into
    ``d2s``): the agents after a in its env, then those before. Returns their count.
    Branch-free: whether a neighbour is within the cut is a coin toss in a dense crowd (one not
    within it is written and then overwritten). The distance is the pair's whichever side
    computes it (``x_a - x_j`` is ``x_j - x_a`` negated, exactly)."""
    base = a - a % n
    count = 0
    for j in range(a + 1, base + n):
        count = _consider(a, j, x, cut, cand, d2s, count)
    for j in range(base, a):
        count = _consider(a, j, x, cut, cand, d2s, count)
    return count


@njit(cache=True, inline="always")
def _consider(a, j, x, cut, cand, d2s, count):
    dx, dy = x[a, 0] - x[j, 0], x[a, 1] - x[j, 1]
    d2 = dx * dx + dy * dy
    cand[count] = j
    d2s[count] = d2
    return count + (np.sqrt(d2) <= cut)


@njit(cache=True, inline="always")
def _cap(a, n, x, g, pref0, r, held, tau, cut, pref):
    """Agent a's preferred velocity with the arrival cap into ``pref`` (``rorca._capped``), its
    neighbours within ``cut`` scanned only where the cap can apply."""
    wanted, speed, dist = cap_wanted(a, x, g, pref0, tau, held)
    gap = np.inf
    if wanted:
        base = a - a % n
        for j in range(base, base + n):
            dx, dy = x[a, 0] - x[j, 0], x[a, 1] - x[j, 1]
            if j != a and np.sqrt(dx * dx + dy * dy) <= cut:
                gap = min(gap, goal_gap(a, j, x, g, r))
    cap_write(a, pref0, wanted, speed, dist, tau, gap, pref)


@njit(cache=True, inline="always")
def _agent(a, n, x, v, pref, r, W, tied, park, settings, space, out):
    """Agent a's R-ORCA velocity (before the speed clip) into out[a], as the grid stage gives
    it: the half-planes of its K nearest candidates (ties: the earlier), solved within the speed
    disk with the sidestep. ``W``: the weight matrices as (E * N, N)."""
    K, u_max, tau, dt, cut = settings
    rows, near, cand, d2s = space
    count = _candidates(a, n, x, cut, cand, d2s)
    keep = count if K < 0 else min(K, count)
    bound, last = np.inf, count
    if keep < count:
        filled = 0
        for c in range(count):
            filled = insert_nearest(near, filled, keep, d2s[c], c)
        bound, last = near[keep - 1, 0], near[keep - 1, 1]
    base = a - a % n
    nrows = 0
    for c in range(count):
        if keep < count and (d2s[c] > bound or (d2s[c] == bound and c > last)):
            continue
        j = cand[c]
        first, second = min(a, j), max(a, j)
        w0, w1 = W[first, second - base], W[second, first - base]
        avoid, slack = shares(tied, park, first, second, w0, w1, a < j)
        vo = pref[j] if park[a] and not park[j] else v[j]
        rows[nrows, 0], rows[nrows, 1], rows[nrows, 2] = plane(
            x, v, r, a, j, vo, avoid, slack, 1.0 / tau, dt
        )
        nrows += 1
    solve(pref[a, 0], pref[a, 1], rows, nrows, u_max, out[a])


@njit(cache=True)
def _space(n, K):
    rows, near = scratch(n - 1, K)
    return rows, near, np.empty(max(n - 1, 1), dtype=np.int64), np.empty(max(n - 1, 1))


@njit(cache=True)
def _stage_serial(n, motion, W, tied, park, held, settings, pref, out):
    """R-ORCA for every agent of envs of ``n``: ``motion`` (x, v, goals, preferred, radii),
    flat (E * n, ...); ``settings`` (K, u_max, tau, dt, cut); the capped preferred velocities
    into ``pref``."""
    x, v, g, pref0, r = motion
    tau, cut = settings[2], settings[4]
    M = x.shape[0]
    for a in range(M):
        _cap(a, n, x, g, pref0, r, held, tau, cut, pref)
    space = _space(n, settings[0])
    for a in range(M):
        _agent(a, n, x, v, pref, r, W, tied, park, settings, space, out)


@njit(cache=True, parallel=True)
def _stage_parallel(n, motion, W, tied, park, held, settings, pref, out):
    """:func:`_stage_serial` over chunks of agents in parallel."""
    x, v, g, pref0, r = motion
    tau, cut = settings[2], settings[4]
    M = x.shape[0]
    chunk = 64
    blocks = (M + chunk - 1) // chunk
    for c in prange(blocks):
        for a in range(c * chunk, min(M, (c + 1) * chunk)):
            _cap(a, n, x, g, pref0, r, held, tau, cut, pref)
    for c in prange(blocks):
        space = _space(n, settings[0])
        for a in range(c * chunk, min(M, (c + 1) * chunk)):
            _agent(a, n, x, v, pref, r, W, tied, park, settings, space, out)


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
