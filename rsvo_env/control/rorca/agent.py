"""One agent's R-ORCA velocity, in pieces both compiled stages share (``rsvo_env.control.rorca``
over flat pair lists, ``rsvo_env.control.rorca.dense`` over each env's agents): its half-plane
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
# the default reach of the goal rule (a scenario's ``rorca_goal_reach``): an agent held within
# this many of its radii of its goal (1: the goal under its own body) yields as if parked
# (rorca.goal_blocked): 1 to 4 measured (docs/liveness.md); at 3 the crowds of 1,000 come in
# quickest with every agent home, at 4 one agent is left short; 0 turns the rule off
GOAL_REACH = 3.0


@njit(cache=True, inline="always")
def plane(mine, other, vo, R, avoid, slack, inv_tau, dt):
    """An agent's R-ORCA half-plane against a neighbour as a row ``(ax, ay, b)`` of
    ``A . v <= b``, ``(ax, ay)`` a unit normal (eq. ``rorca``): ``mine`` the agent's (x, y, vx,
    vy), ``other`` the neighbour's position, ``vo`` the velocity at which the agent reads it
    (``seen``), ``R`` the sum of their radii, ``avoid`` the agent's share of the avoidance,
    ``slack`` of the slack. Scalars in and out: see ``seen``."""
    rx, ry = other[0] - mine[0], other[1] - mine[1]
    wx0, wy0 = mine[2] - vo[0], mine[3] - vo[1]
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
    px, py = mine[2] + sh * cx, mine[3] + sh * cy
    # the half-plane det(d, point - v) <= 0 as a row
    return dy, -dx, dy * px - dx * py


@njit(cache=True, inline="always")
def seen(me_parked, other_parked, pref_x, pref_y, v_x, v_y):
    """The velocity at which an agent reads a neighbour: the neighbour's preferred one
    (``pref_x``, ``pref_y``) where the agent is parked and the neighbour is not
    (``shares``), else its current one. Scalars in and out: an array row is a view, and a
    view, or an array handed to an inlined function, costs atomic reference counts, as much as
    the row's arithmetic."""
    if me_parked and not other_parked:
        return pref_x, pref_y
    return v_x, v_y


@njit(cache=True, inline="always")
def shares(tied, park_first, park_second, w0, w1, me_first):
    """(avoid, slack): an agent's shares against a neighbour in the pair (first, second) whose
    weights are ``w0`` (first's) and ``w1`` (second's), ``park_first`` and ``park_second``
    whether each is parked; ``me_first``: the agent is the pair's first. With the parked rule
    (``tied``), an agent parked on its goal takes all of the avoidance from one en route,
    reading it at its preferred velocity so as to step aside before it is pushed: an egoist at
    rest would otherwise stand as a wall (the shares still sum to 1)."""
    if tied:
        s0 = 1.0 - w0
        if park_first and not park_second:
            s0 = 1.0
        elif park_second and not park_first:
            s0 = 0.0
        s1 = 1.0 - s0
    else:
        s0, s1 = 1.0 - w0, 1.0 - w1
    return (s0, s1) if me_first else (s1, s0)


@njit(cache=True, inline="always")
def solve(px, py, rows, nrows, u_max, bisectors):
    """The velocity (x, y) closest to (px, py) within ``rows[:nrows]`` and the speed disk
    ``u_max`` (ORCA's linear programs, ``rsvo_env.qp.disk.solve``; the least-violating one
    of the disk where they leave no room); ``bisectors`` its scratch. Held below ``SIDESTEP`` of
    its preferred speed, the agent takes the velocity closest to the preferred one turned right
    instead (the sidestep: a held agent keeps moving)."""
    x, y, _ = disk.solve(px, py, rows, nrows, u_max, bisectors)
    if np.sqrt(x * x + y * y) < SIDESTEP * np.sqrt(px * px + py * py):
        x, y, _ = disk.solve(py, -px, rows, nrows, u_max, bisectors)
    return x, y


@njit(cache=True, inline="always")
def cap_wanted(pref, x, goal, held, tau):
    """(wanted, speed, dist): whether an agent's arrival cap can apply (only then can the gap to
    a neighbour tell), its preferred speed and its goal distance; ``pref``, ``x``, ``goal`` its
    preferred velocity, position and goal as pairs of scalars (``seen`` says why)."""
    speed = np.sqrt(pref[0] * pref[0] + pref[1] * pref[1])
    gx, gy = goal[0] - x[0], goal[1] - x[1]
    dist = np.sqrt(gx * gx + gy * gy)
    return held and speed * tau > ARRIVE * dist, speed, dist


@njit(cache=True, inline="always")
def goal_gap(goal, other, r_me, r_other):
    """The gap between an agent's ``goal`` and the body of a neighbour at ``other``."""
    dx, dy = goal[0] - other[0], goal[1] - other[1]
    return np.sqrt(dx * dx + dy * dy) - r_me - r_other


@njit(cache=True, inline="always")
def blocked(x, goal, radius, held, reach):
    """Whether an agent ``held`` short of its goal has it within ``reach`` of its own
    ``radius`` (``rorca.goal_blocked``, the same arithmetic): then it yields as if parked."""
    dx, dy = goal[0] - x[0], goal[1] - x[1]
    return held and np.sqrt(dx * dx + dy * dy) <= reach * radius


@njit(cache=True, inline="always")
def counts_parked(tied, parked, x, goal, radius, held, reach):
    """Whether R-ORCA's parked rule (on where ``tied``) treats an agent as parked: ``parked`` on
    its goal, or held short of a goal within its ``reach`` (``blocked``)."""
    return tied and (parked or blocked(x, goal, radius, held, reach))


@njit(cache=True, inline="always")
def cap_scale(wanted, speed, dist, tau, gap):
    """The factor of an agent's preferred velocity: ``ARRIVE dist / (tau speed)`` where the
    look-ahead ``speed tau`` passes the goal by more than the ``gap``, else 1."""
    scale = 1.0
    if wanted and speed * tau - dist > gap:
        scale = ARRIVE * dist / (tau * speed)
    return scale


@njit(cache=True)
def within(cut):
    """The largest squared distance whose square root is at most ``cut``: ``d2 <= within(cut)``
    decides ``sqrt(d2) <= cut`` exactly (a correctly rounded square root is monotone) without a
    square root."""
    T = cut * cut
    while T > 0.0 and np.sqrt(T) > cut:
        T = np.nextafter(T, -np.inf)
    while T < np.inf and np.sqrt(np.nextafter(T, np.inf)) <= cut:
        T = np.nextafter(T, np.inf)
    return T


@njit(cache=True)
def scratch(width, K):
    """An agent's rows (its K nearest of at most ``width``) and the solver's scratch (as many)."""
    kept = max(width if K < 0 else min(width, K), 1)
    return np.empty((kept, 3)), np.empty((kept, 3))
