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
limit (an octagon inscribed in the disk), solved exactly by ``rsvo_env.qp.exact``; an
empty polygon gives the least-violating velocity (ORCA's third linear program). The R-CBF
filter on top keeps the guarantee whatever this controller proposes.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from rsvo_env.geometry import pairs
from rsvo_env.qp import exact
from rsvo_env.responsibility.svo import Weighting
from rsvo_env.util import sizes, threads
from rsvo_env.util.planar import clip_norm

# below this fraction of its preferred speed an agent counts as held still (it sidesteps)
SIDESTEP = 0.0625
# near its goal, where its look-ahead passes the goal and reaches a neighbour's body, an agent
# that has come no closer to its goal for HOLD_SECONDS prefers at most ARRIVE times its goal
# distance per horizon tau: held for tau, as the half-planes assume, its preferred velocity then
# ends at most one goal distance past the goal. Faster (move-to-goal's k = 2 with tau = 2 runs 4
# goal distances), agents parked beyond the goal fill the look-ahead and an agent can orbit its
# goal for good; an agent still closing in keeps its speed (docs/liveness.md)
ARRIVE = 2.0
HOLD_SECONDS = 0.3
# the speed limit as an octagon inscribed in its disk: 8 unit normals, the offset u_max cos(pi/8)
_OCTAGON = np.stack(
    [np.cos(np.arange(8) * np.pi / 4), np.sin(np.arange(8) * np.pi / 4)], axis=-1
)


@njit(cache=True, inline="always")
def _plane(x, v, radii, me, other, vo, avoid, slack, inv_tau, dt):
    """Agent ``me``'s R-ORCA half-plane against ``other`` (read at velocity ``vo``) as a row
    ``(ax, ay, b)`` of ``A . v <= b``, ``(ax, ay)`` a unit normal: ``avoid`` its share of the
    avoidance, ``slack`` of the slack (eq. ``rorca``)."""
    rx, ry = x[other, 0] - x[me, 0], x[other, 1] - x[me, 1]
    wx0, wy0 = v[me, 0] - vo[0], v[me, 1] - vo[1]
    R = radii[me] + radii[other]
    d2, R2 = rx * rx + ry * ry, R * R
    if d2 > R2:
        wx, wy = wx0 - inv_tau * rx, wy0 - inv_tau * ry
        w2 = wx * wx + wy * wy
        dot1 = wx * rx + wy * ry
        if dot1 < 0.0 and dot1 * dot1 > R2 * w2:  # the cutoff circle
            wl = np.sqrt(w2)
            ux, uy = wx / wl, wy / wl
            dx, dy = uy, -ux
            s = R * inv_tau - wl
            cx, cy = s * ux, s * uy
        else:  # a leg
            leg = np.sqrt(d2 - R2)
            if rx * wy - ry * wx > 0.0:
                dx, dy = (rx * leg - ry * R) / d2, (rx * R + ry * leg) / d2
            else:
                dx, dy = -(rx * leg + ry * R) / d2, -(-rx * R + ry * leg) / d2
            dot2 = wx0 * dx + wy0 * dy
            cx, cy = dot2 * dx - wx0, dot2 * dy - wy0
    else:  # overlapping: leave within one step
        wx, wy = wx0 - rx / dt, wy0 - ry / dt
        wl = np.sqrt(wx * wx + wy * wy)
        ux, uy = (wx / wl, wy / wl) if wl > 0.0 else (1.0, 0.0)
        dx, dy = uy, -ux
        s = R / dt - wl
        cx, cy = s * ux, s * uy
    # A . u > 0 (A the row below): the current velocity already meets the row, and u is room
    # left to close (slack), not avoidance
    sh = avoid if dy * cx - dx * cy <= 0.0 else slack
    px, py = v[me, 0] + sh * cx, v[me, 1] + sh * cy
    # the half-plane det(d, point - v) <= 0 as a row
    return dy, -dx, dy * px - dx * py


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
            row = _plane(x, v, radii, me, other, vo, share[p, side], share[p, 1 - side],
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
    px, py = pref[a, 0], pref[a, 1]
    speed = np.sqrt(px * px + py * py)
    gx, gy = g[a, 0] - x[a, 0], g[a, 1] - x[a, 1]
    dist = np.sqrt(gx * gx + gy * gy)
    scale = 1.0
    if held[a] and speed * tau > ARRIVE * dist:  # only then can the gap to a neighbour tell
        gap = np.inf
        for k in range(offsets[a], offsets[a + 1]):
            j = other[k]
            dx, dy = g[a, 0] - x[j, 0], g[a, 1] - x[j, 1]
            gap = min(gap, np.sqrt(dx * dx + dy * dy) - r[a] - r[j])
        if speed * tau - dist > gap:
            scale = ARRIVE * dist / (tau * speed)
    out[a, 0], out[a, 1] = px * scale, py * scale


@njit(cache=True, inline="always")
def _agent(a, x, v, pref, r, lists, w, tied, park, settings, octagon, rows, near, out):
    """Agent a's R-ORCA velocity (before the speed clip) into out[a]: the half-planes of its
    ``K`` nearest candidates (ties: the earlier in its list), the ``octagon`` (its 8 rows,
    normalised), the exact QP, and the sidestep where the half-planes hold it still.
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
        # the K nearest, by an insertion sort into near[:keep] (K is ORCA's 10); each squared
        # distance kept in near[:, 2] for the pass below
        filled = 0
        for k in range(start, stop):
            j = other[k]
            dx, dy = x[a, 0] - x[j, 0], x[a, 1] - x[j, 1]
            d2 = dx * dx + dy * dy
            near[k - start, 2] = d2
            if filled == keep and d2 >= near[keep - 1, 0]:
                continue
            pos = min(filled, keep - 1)
            while pos > 0 and near[pos - 1, 0] > d2:
                near[pos, 0], near[pos, 1] = near[pos - 1, 0], near[pos - 1, 1]
                pos -= 1
            near[pos, 0], near[pos, 1] = d2, k
            filled = min(filled + 1, keep)
        bound, last = near[keep - 1, 0], near[keep - 1, 1]
    nrows = 0
    for k in range(start, stop):
        if keep < count:
            d2 = near[k - start, 2]
            if d2 > bound or (d2 == bound and k > last):
                continue
        j = other[k]
        p = pair[k]
        if tied:
            # an agent parked on its goal takes all of the avoidance from one en route, reading
            # it at its preferred velocity so as to step aside before it is pushed: an egoist at
            # rest would otherwise stand as a wall (the shares still sum to 1)
            first, second = (a, j) if side[k] == 0 else (j, a)
            s0 = 1.0 - w[p, 0]
            if park[first] and not park[second]:
                s0 = 1.0
            elif park[second] and not park[first]:
                s0 = 0.0
            s1 = 1.0 - s0
        else:
            s0, s1 = 1.0 - w[p, 0], 1.0 - w[p, 1]
        avoid, slack = (s0, s1) if side[k] == 0 else (s1, s0)
        vo = pref[j] if park[a] and not park[j] else v[j]
        # a unit normal by construction (a leg's or the cutoff circle's direction): stored as
        # it is, where normalising it again would cost as much as the QP
        rows[nrows, 0], rows[nrows, 1], rows[nrows, 2] = _plane(
            x, v, r, a, j, vo, avoid, slack, inv_tau, dt
        )
        nrows += 1
    rows[nrows : nrows + 8] = octagon
    nrows += 8
    px, py = pref[a, 0], pref[a, 1]
    res = out[a]
    exact.solve_point(px, py, rows, nrows, -u_max, -u_max, u_max, u_max, res)
    # an agent the half-planes hold still while it wants to move (a jam that is symmetric, as
    # in a ring around a common goal) sidesteps: the velocity closest to its preferred one
    # turned to its right, which the half-planes of touching neighbours let it take
    if np.sqrt(res[0] * res[0] + res[1] * res[1]) < SIDESTEP * np.sqrt(px * px + py * py):
        exact.solve_point(py, -px, rows, nrows, -u_max, -u_max, u_max, u_max, res)


@njit(cache=True)
def _octagon(u_max):
    """The speed limit's 8 rows, normalised as :func:`exact.set_row` stores them."""
    rows = np.empty((8, 3))
    edge = u_max * np.cos(np.pi / 8)
    for q in range(8):
        exact.set_row(rows, q, _OCTAGON[q, 0], _OCTAGON[q, 1], edge)
    return rows


@njit(cache=True)
def _widest_list(offsets):
    widest = 0
    for a in range(offsets.shape[0] - 1):
        widest = max(widest, offsets[a + 1] - offsets[a])
    return widest


@njit(cache=True)
def _scratch(width, K):
    """An agent's row space (its K nearest and the octagon) and the insertion's (every
    candidate), for lists of at most ``width``."""
    kept = width if K < 0 else min(width, K)
    return np.empty((kept + 8, 3)), np.empty((max(width, 1), 3))


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
    octagon = _octagon(settings[1])
    rows, near = _scratch(width, K)
    for a in range(M):
        _agent(a, x, v, pref, r, lists, w, tied, park, settings, octagon, rows, near, out)


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
    octagon = _octagon(settings[1])
    for c in prange(blocks):
        rows, near = _scratch(width, K)
        for a in range(c * chunk, min(M, (c + 1) * chunk)):
            _agent(a, x, v, pref, r, lists, w, tied, park, settings, octagon, rows, near, out)


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
    """(...,) the agents ``held`` short of a goal that lies under their own bodies (``radii``),
    which R-ORCA treats as parked. A neighbour's body blocks such a goal, and an agent pressing
    for it pins that neighbour, which may be the very agent that must pass to free the goal
    (the crowd of 100 at its defaults, seed 3: an egoist 0.15 m short of its goal pinned an
    altruist between two parked agents for 20,000 steps). Parked, it yields, the neighbour
    passes, and it comes back (``docs/liveness.md``)."""
    d = goals - positions
    return held & (np.sqrt(d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1]) <= radii)


class Rules(NamedTuple):
    """The state R-ORCA's rules read beyond the crowd's motion: ``parked`` (E, N) agents at
    their goals, ``goals`` (E, N, 2), ``held`` (E, N) agents held short of them."""

    parked: NDArray | None = None
    goals: NDArray | None = None
    held: NDArray | None = None


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
    ``held`` (E, N) if given; these three are ``rules`` (:class:`Rules`, None: none of them)."""
    parked, goals, held = (None, None, None) if rules is None else rules
    E, n = positions.shape[:2]
    M = E * n
    radii = np.broadcast_to(radii, (E, n))
    if neighbor_dist is None:
        neighbor_dist = 10.0 * float(radii.max())
    flat = lambda a: np.ascontiguousarray(a, dtype=np.float64).reshape(M, -1)  # noqa: E731
    x, v, pref0 = flat(positions), flat(velocities), flat(preferred)
    if n <= sizes.DENSE_MAX_AGENTS:  # every pair, cut to neighbor_dist in the compiled pass
        (I, J), cut = pairs.all_pairs(n, E), float(neighbor_dist)
    else:
        (I, J), cut = pairs.candidate_pairs(positions, neighbor_dist), np.inf
    w = np.ascontiguousarray(pairs.weights_of(theta, modes, I, J))
    lists = _neighbor_lists(I, J, x, cut, M)
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
    settings = (K, float(u_max), float(tau), float(dt))
    threads.launch(
        _stage_serial, _stage_parallel, M, (x, v, g, pref0, r), lists, w, parked is not None,
        park, hold, settings, pref, out,
    )  # fmt: skip
    # where the half-planes leave no room the least-violating point may lie past the octagon
    # (its rows are relaxed too): the speed limit holds regardless
    return clip_norm(out, u_max).reshape(E, n, 2)
