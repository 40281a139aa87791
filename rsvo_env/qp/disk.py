"""The velocity closest to a preferred one within half-planes and a speed disk, in 2-D (numba):
ORCA's own linear programs (van den Berg et al., 2011; RVO2's ``linearProgram1`` to ``3``), for
R-ORCA (``rsvo_env.control.rorca``).

``min |v - p|^2`` s.t. ``a_k . v <= b_k`` (unit normals ``a_k``) and ``|v| <= r``. Start at ``p``
clipped to the disk and add the rows one by one; a row the current point violates moves the
optimum onto that row's line (Seidel's argument, as in ``rsvo_env.qp.exact``), where the
problem is 1-D: the chord of the disk on the line, cut by the rows before it. Where the
half-planes leave no room within the disk, the velocity is the one of the disk whose largest
violation ``max_k (a_k . v - b_k)`` is least (``linearProgram3``): each row violated beyond the
current worst moves the optimum onto the set where that row is the worst, a 2-D program in its
own right whose rows are the bisectors with the rows before it.

Two lines at an angle whose sine is at most ``PARALLEL`` are taken as parallel, as RVO2 does with
its ``RVO_EPSILON``; here the threshold is on unit normals, so it is scale-free: along the chord
(length at most 2 r) such a row's value changes by at most ``2 PARALLEL r``, so deciding it for
the whole chord by its value at the line's nearest point costs at most ``4 PARALLEL r`` of that
row, where computing the crossing of two nearly coincident lines would cut the chord anywhere
(rounding over rounding). Every other comparison is scale-free too: the rows' offsets and ``r``
carry the units, so a crowd in millimetres gets the same velocities as one in metres, scaled.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rsvo_env.qp.least_violation import max_violation

PARALLEL = 1e-13
# a chord that rounds to a point is kept if no row is violated by more than ROOM r there
ROOM = 1e-13


@njit(cache=True, inline="always")
def _on_line(rows, k, r, px, py, toward):
    """The point of row k's line within the disk and the rows before k closest to (px, py)
    (``toward`` False), or furthest along the direction (px, py) (``toward`` True): (x, y, ok).

    A chord that rounds to a point (lines through one point, a line tangent to the disk) can
    come out a hair empty or a hair outside the disk; it is read as empty only where, at the
    point of the chord where the largest violation of the rows before k is least, a row or the
    disk is violated by more than ``ROOM r`` (``_balanced``)."""
    ax, ay, bk = rows[k, 0], rows[k, 1], rows[k, 2]
    disc = (r - bk) * (r + bk)  # not r^2 - b^2: a line that barely cuts the disk keeps its chord
    if disc < 0.0:
        if abs(bk) - r > ROOM * r:
            return 0.0, 0.0, False
        disc = 0.0  # tangent to the disk within rounding: its one point
    root = np.sqrt(disc)
    # the line: (ox, oy) + t (dx, dy), (ox, oy) its point nearest the disk's centre
    ox, oy, dx, dy = bk * ax, bk * ay, -ay, ax
    lo, hi = -root, root
    slope_lo, slope_hi = np.inf, np.inf  # how fast the rows setting lo and hi (none: the disk)
    for m in range(k):
        denom = rows[m, 0] * dx + rows[m, 1] * dy
        numer = rows[m, 2] - (rows[m, 0] * ox + rows[m, 1] * oy)
        if abs(denom) <= PARALLEL:  # all of the chord meets row m, or none of it
            if numer < -2.0 * PARALLEL * r:
                return 0.0, 0.0, False
            continue
        if denom > 0.0:
            if numer / denom < hi:
                hi, slope_hi = numer / denom, denom
        elif numer / denom > lo:
            lo, slope_lo = numer / denom, -denom
    if lo > hi:
        # the two rows setting lo and hi alone are violated by at least this between them
        gap = lo - hi
        if slope_lo == np.inf or slope_hi == np.inf:
            least = gap * min(slope_lo, slope_hi)
        else:
            least = gap * slope_lo * slope_hi / (slope_lo + slope_hi)
        if least > ROOM * r:
            return 0.0, 0.0, False
        t = _balanced(rows, k, r, root, lo, hi, ox, oy, dx, dy)
        if np.isnan(t):
            return 0.0, 0.0, False
    elif toward:
        t = hi if px * dx + py * dy > 0.0 else lo
    else:
        t = min(max(dx * (px - ox) + dy * (py - oy), lo), hi)
    return ox + t * dx, oy + t * dy, True


@njit(cache=True, inline="always")
def _balanced(rows, k, r, root, lo, hi, ox, oy, dx, dy):
    """Where the chord's bounds crossed (``lo > hi``): the point ``t`` of the chord between
    them at which the largest violation of the rows before k is least, if that violation is at
    most ``ROOM r`` (the rounding of lines through one point) and the point is within the disk
    to ``ROOM r`` (a tangent line's rounding); else NaN.

    The largest violation along the line is convex in ``t`` (a maximum of lines), so a ternary
    search finds its least; the crossings that set ``lo`` and ``hi`` alone would not do, since
    the crossing of a nearly parallel row can be far off where its violation is not."""
    a, b = max(hi, -root), min(lo, root)
    for _ in range(100):
        t1, t2 = a + (b - a) / 3.0, b - (b - a) / 3.0
        if max_violation(ox + t1 * dx, oy + t1 * dy, rows, k) <= max_violation(
            ox + t2 * dx, oy + t2 * dy, rows, k
        ):
            b = t2
        else:
            a = t1
    t = 0.5 * (a + b)
    x, y = ox + t * dx, oy + t * dy
    allowed = ROOM * r
    if np.sqrt(x * x + y * y) - r > allowed or max_violation(x, y, rows, k) > allowed:
        return np.nan
    return t


@njit(cache=True, inline="always")
def _program(rows, nrows, r, px, py, toward):
    """``linearProgram2``: (x, y, failed) with ``failed`` the first row that leaves no room
    (``nrows`` if none); (x, y) the optimum of the rows before it."""
    if toward:  # the disk's point furthest along the unit direction (px, py)
        x, y = px * r, py * r
    else:
        x, y = px, py
        norm = np.sqrt(px * px + py * py)
        if norm > r:
            x, y = px / norm * r, py / norm * r
    for k in range(nrows):
        if rows[k, 0] * x + rows[k, 1] * y > rows[k, 2]:
            nx, ny, ok = _on_line(rows, k, r, px, py, toward)
            if not ok:
                return x, y, k
            x, y = nx, ny
    return x, y, nrows


@njit(cache=True)
def _least_violation(rows, nrows, begin, r, x, y, bisectors):
    """``linearProgram3``: from the optimum (x, y) of the rows before ``begin``, the point of the
    disk whose largest violation is least; ``bisectors`` scratch (nrows, 3)."""
    worst = 0.0
    for i in range(begin, nrows):
        ax, ay, bi = rows[i, 0], rows[i, 1], rows[i, 2]
        if ax * x + ay * y - bi <= worst:
            continue
        # row m's violation at most row i's: (a_m - a_i) . v <= b_m - b_i, normalised
        count = 0
        for m in range(i):
            cx, cy = rows[m, 0] - ax, rows[m, 1] - ay
            norm = np.sqrt(cx * cx + cy * cy)
            if norm <= PARALLEL:  # the same normal: their violations differ by a constant
                continue
            bisectors[count, 0] = cx / norm
            bisectors[count, 1] = cy / norm
            bisectors[count, 2] = (rows[m, 2] - bi) / norm
            count += 1
        nx, ny, failed = _program(bisectors, count, r, -ax, -ay, True)
        if failed == count:  # rounding can empty the program; then the point stays
            x, y = nx, ny
        worst = ax * x + ay * y - bi
    return x, y


@njit(cache=True, inline="always")
def solve(px, py, rows, nrows, r, bisectors):
    """The velocity closest to (px, py) within ``rows[:nrows]`` (``a . v <= b``, unit normals)
    and the disk ``|v| <= r``; where they leave no room, the least-violating velocity of the
    disk. ``bisectors``: scratch (nrows, 3). Returns (x, y, whether there was room); scalars, not
    an array row: a view of an array costs two atomic reference counts, as much as the solve."""
    x, y, failed = _program(rows, nrows, r, px, py, False)
    if failed < nrows:
        x, y = _least_violation(rows, nrows, failed, r, x, y, bisectors)
    return x, y, failed == nrows


@njit(cache=True)
def solve_disk(px, py, rows, nrows, r, bisectors, res):
    """``solve`` into ``res``; returns whether there was room."""
    res[0], res[1], room = solve(px, py, rows, nrows, r, bisectors)
    return room
