"""R-ORCA's jam routing: a preferred velocity turned around the knots ahead
(``docs/liveness.md``, "Routing around knots").

Behind the filter a knot of agents cannot press through, as ORCA's least violation does (bodies
overlapping), and an agent that walks into one joins it: in a crowd of 10,000 the knots grow
through the second minute until a third of the crowd stands in them. So each agent en route
farther than ``LOOK`` safety radii from its goal counts the *slow* agents (en route, slower than
``SLOW`` of the speed limit) within ``PROBE`` safety radii of the point ``LOOK`` radii ahead
toward its goal. Where there are at least ``CROWDED``, it counts them ahead of each heading of
``TURNS`` as well and takes the heading whose count plus ``TURN_COST`` per degree of turn is
least (ties: the earlier of ``TURNS``: straight on, then right before left, the right-hand
rule's side), its preferred velocity turned by that angle. Every length is in safety radii, so
the rule reads the same in any unit. The turn changes only what the agent asks: the filter's
rows, and with them the guarantee, are untouched. Routing is R-ORCA's way around a knot where
it is on; the right-hand rule is then its last resort, for agents that have come no closer to
their goals for ``RH_HOLD`` seconds (the scenario's ``rh_hold`` default). The crowd routes by
default (``rsvo_env.scenarios.crowd``), R-ORCA's rules set for it.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env.util.grid import build_cells, cell_span
from rsvo_env.util.validation import check_positive

LOOK = 6.0  # safety radii from the agent to the point it probes
PROBE = 4.0  # safety radii around that point
SLOW = 0.5  # of the speed limit: an agent en route slower than this counts as stuck
CROWDED = 5  # stuck agents ahead that make an agent look for another heading
TURN_COST = 0.05  # stuck agents a degree of turn is worth
TURNS = (0.0, -30.0, 30.0, -60.0, 60.0, -90.0, 90.0)  # degrees, counterclockwise positive
RH_HOLD = 5.0  # s: routed, the right-hand rule turns only agents stalled this long
# each heading of TURNS as (cos, sin, |degrees|), what every probe reads
HEADINGS = (np.cos(np.deg2rad(TURNS)), np.sin(np.deg2rad(TURNS)), np.abs(np.array(TURNS)))


def routed(
    positions: NDArray[np.float64],
    velocities: NDArray[np.float64],
    goals: NDArray[np.float64],
    at_goal: NDArray[np.bool_],
    preferred: NDArray[np.float64],
    scale: float,
    speed: float,
) -> NDArray[np.float64]:
    """The preferred velocities (E, N, 2) turned around the knots ahead (module docstring):
    ``positions``, ``velocities``, ``goals``, ``preferred`` (E, N, 2), ``at_goal`` (E, N),
    ``scale`` the safety radius, ``speed`` the speed limit."""
    f = lambda a: np.ascontiguousarray(a, dtype=np.float64)  # noqa: E731
    x, v, g, pref = f(positions), f(velocities), f(goals), f(preferred)
    shape = pref.shape
    if not (x.shape == v.shape == g.shape == shape and 2 <= len(shape) <= 3 and shape[-1] == 2):
        shapes = {"positions": x.shape, "velocities": v.shape, "goals": g.shape, "preferred": shape}
        raise ValueError(f"routed: {shapes} must be one shape, (E, N, 2) or (N, 2)")
    if np.shape(at_goal) != shape[:-1]:
        raise ValueError(f"routed: at_goal has shape {np.shape(at_goal)}, expected {shape[:-1]}")
    scale, speed = check_positive(scale, "routed: scale"), check_positive(speed, "routed: speed")
    E = 1 if x.ndim == 2 else x.shape[0]
    n = x.shape[-2]
    out = pref.reshape(E, n, 2).copy()
    route_envs(
        x.reshape(E, n, 2),
        v.reshape(E, n, 2),
        g.reshape(E, n, 2),
        np.ascontiguousarray(at_goal, np.bool_).reshape(E, n),
        scale,
        SLOW * speed,
        *HEADINGS,
        out,
    )
    return out.reshape(shape)


@njit(cache=True)
def route_envs(x, v, g, at_goal, scale, slow_speed, cos_t, sin_t, degrees, out):
    """``routed`` env by env: the stuck agents in the spatial grid (``util.grid``) of cells
    a probe's diameter wide (a probe's disk touches two per axis, so it visits four; cells of
    its radius, nine to visit), wider where the stuck agents are spread thin (the cells number
    at most four per stuck agent); each probe a scan of the cells its disk touches."""
    E, n = x.shape[0], x.shape[1]
    look, probe = LOOK * scale, PROBE * scale
    for e in range(E):
        stuck = np.empty(n, np.int64)
        m = 0
        for i in range(n):
            s2 = v[e, i, 0] * v[e, i, 0] + v[e, i, 1] * v[e, i, 1]
            if not at_goal[e, i] and s2 < slow_speed * slow_speed:
                stuck[m] = i
                m += 1
        if m < CROWDED:
            continue
        pts = np.empty((m, 2))
        for k in range(m):
            pts[k, 0], pts[k, 1] = x[e, stuck[k], 0], x[e, stuck[k], 1]
        lo_x, lo_y, cell, nx, ny, start, order = build_cells(pts, 2.0 * probe)
        # the stuck agents' positions in cell order: a probe reads them contiguously
        xs = pts[order]
        grid = (lo_x, lo_y, cell, nx, ny)
        for i in range(n):
            if at_goal[e, i]:
                continue
            dx, dy = g[e, i, 0] - x[e, i, 0], g[e, i, 1] - x[e, i, 1]
            dist = np.sqrt(dx * dx + dy * dy)
            if dist <= look:
                continue
            ux, uy = dx / dist, dy / dist
            ahead = _count(
                xs, start, grid, x[e, i, 0] + look * ux, x[e, i, 1] + look * uy, probe, n
            )
            if ahead < CROWDED:
                continue
            best, cost = 0, float(ahead)
            for t in range(1, cos_t.shape[0]):
                hx, hy = cos_t[t] * ux - sin_t[t] * uy, sin_t[t] * ux + cos_t[t] * uy
                # a heading wins only with fewer than this many: the scan stops when it has them
                need = cost - TURN_COST * degrees[t]
                if need <= 0.0:
                    continue
                limit = int(np.ceil(need))
                c = _count(
                    xs, start, grid, x[e, i, 0] + look * hx, x[e, i, 1] + look * hy, probe, limit
                )
                if c < limit and c + TURN_COST * degrees[t] < cost:
                    best, cost = t, c + TURN_COST * degrees[t]
            px, py = out[e, i, 0], out[e, i, 1]
            out[e, i, 0] = cos_t[best] * px - sin_t[best] * py
            out[e, i, 1] = sin_t[best] * px + cos_t[best] * py


@njit(cache=True)
def _count(xs, start, grid, px, py, radius, limit):
    """The stuck agents (positions ``xs`` in cell order, ``start`` each cell's first) within
    ``radius`` of the point (px, py), or ``limit`` once the count reaches it (the caller needs
    no more). Cells the disk does not reach are skipped."""
    lo_x, lo_y, cell, nx, ny = grid
    r2 = radius * radius
    c0, c1 = cell_span(px, radius, lo_x, cell, nx)
    r0, r1 = cell_span(py, radius, lo_y, cell, ny)
    count = 0
    for a in range(c0, c1 + 1):
        # the gap from the point to the cell's column, then to the cell
        gx = max(lo_x + a * cell - px, px - lo_x - (a + 1) * cell, 0.0)
        for b in range(r0, r1 + 1):
            gy = max(lo_y + b * cell - py, py - lo_y - (b + 1) * cell, 0.0)
            if gx * gx + gy * gy > r2 * (1.0 + 1e-6):  # the slack: cell edges' rounding
                continue
            c = a * ny + b
            for k in range(start[c], start[c + 1]):
                ex, ey = xs[k, 0] - px, xs[k, 1] - py
                count += ex * ex + ey * ey <= r2
            if count >= limit:
                return limit
    return count
