"""One agent's R-ORCA velocity, in pieces both compiled stages share (``rsvo_env.control.rorca``
over flat pair lists, ``rsvo_env.control.rorca_dense`` over each env's agents): its half-plane
against a neighbour (eq. ``rorca``), its shares of the avoidance and the slack, the K nearest,
the solve within the speed disk with the sidestep, and the arrival cap."""

from __future__ import annotations

import numpy as np
from numba import njit

from rsvo_env.qp import disk

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
# an agent held within this many of its radii of its goal (1: the goal under its own body) yields
# as if parked (rorca.goal_blocked); 2 to 4 measured, quicker crowds of 1,000 but the circular
# swap's egoists no longer first at every size (docs/liveness.md)
GOAL_REACH = 1.0


@njit(cache=True, inline="always")
def plane(x, v, radii, me, other, vo, avoid, slack, inv_tau, dt):
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


@njit(cache=True, inline="always")
def shares(tied, park, first, second, w0, w1, me_first):
    """(avoid, slack): an agent's shares against a neighbour in the pair (``first``,
    ``second``) whose weights are ``w0`` (first's) and ``w1`` (second's); ``me_first``: the
    agent is the pair's first. With the parked rule (``tied``), an agent parked on its goal
    takes all of the avoidance from one en route, reading it at its preferred velocity so as to
    step aside before it is pushed: an egoist at rest would otherwise stand as a wall (the
    shares still sum to 1)."""
    if tied:
        s0 = 1.0 - w0
        if park[first] and not park[second]:
            s0 = 1.0
        elif park[second] and not park[first]:
            s0 = 0.0
        s1 = 1.0 - s0
    else:
        s0, s1 = 1.0 - w0, 1.0 - w1
    return (s0, s1) if me_first else (s1, s0)


@njit(cache=True, inline="always")
def insert_nearest(near, filled, keep, d2, k):
    """One candidate (squared distance ``d2``, position ``k``) into the ``keep`` nearest so far,
    ``near[:filled]`` sorted by distance (ties: the earlier stays first); returns the new fill."""
    if filled == keep and d2 >= near[keep - 1, 0]:
        return filled
    pos = min(filled, keep - 1)
    while pos > 0 and near[pos - 1, 0] > d2:
        near[pos, 0], near[pos, 1] = near[pos - 1, 0], near[pos - 1, 1]
        pos -= 1
    near[pos, 0], near[pos, 1] = d2, k
    return min(filled + 1, keep)


@njit(cache=True, inline="always")
def solve(px, py, rows, nrows, u_max, res):
    """The velocity closest to (px, py) within ``rows[:nrows]`` and the speed disk ``u_max``
    (ORCA's linear programs, :func:`rsvo_env.qp.disk.solve_disk`; the least-violating one of
    the disk where they leave no room) into ``res``; ``rows[nrows:2 nrows]`` its scratch. Held
    below ``SIDESTEP`` of its preferred speed, the agent takes the velocity closest to the
    preferred one turned right instead (the sidestep: a held agent keeps moving)."""
    bisectors = rows[nrows:]
    disk.solve_disk(px, py, rows, nrows, u_max, bisectors, res)
    if np.sqrt(res[0] * res[0] + res[1] * res[1]) < SIDESTEP * np.sqrt(px * px + py * py):
        disk.solve_disk(py, -px, rows, nrows, u_max, bisectors, res)


@njit(cache=True, inline="always")
def cap_wanted(a, x, g, pref, tau, held):
    """(wanted, speed, dist): whether agent a's arrival cap can apply (only then can the gap to
    a neighbour tell), its preferred speed and its goal distance."""
    px, py = pref[a, 0], pref[a, 1]
    speed = np.sqrt(px * px + py * py)
    gx, gy = g[a, 0] - x[a, 0], g[a, 1] - x[a, 1]
    dist = np.sqrt(gx * gx + gy * gy)
    return held[a] and speed * tau > ARRIVE * dist, speed, dist


@njit(cache=True, inline="always")
def goal_gap(a, j, x, g, r):
    """The gap between agent a's goal and neighbour j's body."""
    dx, dy = g[a, 0] - x[j, 0], g[a, 1] - x[j, 1]
    return np.sqrt(dx * dx + dy * dy) - r[a] - r[j]


@njit(cache=True, inline="always")
def cap_write(a, pref, wanted, speed, dist, tau, gap, out):
    """Agent a's preferred velocity into out[a], scaled to ``ARRIVE dist / tau`` where the
    look-ahead ``speed tau`` passes the goal by more than the ``gap``."""
    scale = 1.0
    if wanted and speed * tau - dist > gap:
        scale = ARRIVE * dist / (tau * speed)
    out[a, 0], out[a, 1] = pref[a, 0] * scale, pref[a, 1] * scale


@njit(cache=True)
def scratch(width, K):
    """An agent's row space (its K nearest, then as many rows of the solver's scratch) and the
    insertion's (every candidate), for lists of at most ``width``."""
    kept = width if K < 0 else min(width, K)
    return np.empty((2 * kept + 2, 3)), np.empty((max(width, 1), 3))
