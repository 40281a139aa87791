"""The least largest violation of 2-D half-planes over a box, exactly (numba).

``min_{u in box} max_k (a_k u - b_k)`` (unit normals ``a_k``) is the linear program
``min t`` s.t. ``a_k u - t <= b_k`` over the box in ``(u, t)``, solved by Seidel's incremental
algorithm as ORCA's ``linearProgram3`` solves it (van den Berg et al.): keep the optimum of the
first rows; when row i is violated by more than it, the optimum of the first i + 1 rows lies on
row i's plane ``t = a_i u - b_i``, where the program is 2-D: maximise ``-a_i u`` over the box
with ``(a_m - a_i) u <= b_m - b_i`` for m < i (row i the worst of them), itself solved
incrementally on lines (``_deepest``). Where optima tie (parallel rows), the argument still
holds: the segment of old optima crosses row i's plane. The work is O(K^2) for K rows at worst,
and a handful of 1-D problems for a typical agent, where the bisection it replaces (~45 exact
projections) cost 45 times a feasible QP.
"""

from __future__ import annotations

import numpy as np
from numba import njit

# A row counts as violated beyond the current optimum by more than this, relative to the
# problem's scale (the box's extent and the row's offset), as in ``rsvo_env.qp.exact``.
_EPS = 1e-12


@njit(cache=True, inline="always")
def _towards(d, lo, hi, current):
    """The coordinate in [lo, hi] that maximises d times it (the current one clipped if d = 0)."""
    if d > 0.0:
        return hi
    if d < 0.0:
        return lo
    return min(max(current, lo), hi)


@njit(cache=True)
def _deepest(rows, i, lo0, lo1, hi0, hi1, scale, ux, uy):
    """The point of the box where row i is least violated among those where no earlier row is
    violated more: maximise ``-a_i u`` subject to ``(a_m - a_i) u <= b_m - b_i``, m < i, by
    the incremental 2-D linear program (ORCA's ``linearProgram2`` with ``directionOpt``). The
    start ``(ux, uy)`` breaks ties in a coordinate the objective leaves free. An interval that
    rounding empties gives its middle: Seidel's argument says it is not empty."""
    a0, a1, bi = rows[i, 0], rows[i, 1], rows[i, 2]
    x = _towards(-a0, lo0, hi0, ux)
    y = _towards(-a1, lo1, hi1, uy)
    for m in range(i):
        c0, c1, e = rows[m, 0] - a0, rows[m, 1] - a1, rows[m, 2] - bi
        cn = np.sqrt(c0 * c0 + c1 * c1)
        if cn == 0.0 or c0 * x + c1 * y <= e + _EPS * (scale * cn + abs(e)):
            continue  # met, or parallel to row i (then met wherever row i is the worst)
        n0, n1, em = c0 / cn, c1 / cn, e / cn
        p0x, p0y, dx, dy = em * n0, em * n1, -n1, n0
        slo, shi = -np.inf, np.inf
        for p0c, dc, lc, hc in ((p0x, dx, lo0, hi0), (p0y, dy, lo1, hi1)):
            if dc != 0.0:
                t1, t2 = (lc - p0c) / dc, (hc - p0c) / dc
                slo, shi = max(slo, min(t1, t2)), min(shi, max(t1, t2))
        for q in range(m):
            g0, g1, f = rows[q, 0] - a0, rows[q, 1] - a1, rows[q, 2] - bi
            denom = g0 * dx + g1 * dy
            if denom == 0.0:
                continue  # parallel to line m: it cannot narrow the interval
            bound = (f - (g0 * p0x + g1 * p0y)) / denom
            if denom > 0.0:
                shi = min(shi, bound)
            else:
                slo = max(slo, bound)
        gain = -(a0 * dx + a1 * dy)
        if slo > shi:
            s = 0.5 * (slo + shi)
        elif gain > 0.0:
            s = shi
        elif gain < 0.0:
            s = slo
        else:
            s = min(max(dx * (x - p0x) + dy * (y - p0y), slo), shi)
        x = min(max(p0x + s * dx, lo0), hi0)
        y = min(max(p0y + s * dy, lo1), hi1)
    return x, y


@njit(cache=True)
def min_max(rows, nrows, lo0, lo1, hi0, hi1, scale, ux, uy):
    """``(t, x, y)``: the least largest violation ``t`` of ``rows[:nrows]`` (unit normals) over
    the box and a point ``(x, y)`` of the box that attains it, from the start ``(ux, uy)`` in
    the box; ``t`` is the largest violation at that point, so it bounds the optimum from above
    whatever the rounding."""
    t = -np.inf
    for i in range(nrows):
        b = rows[i, 2]
        if rows[i, 0] * ux + rows[i, 1] * uy - b <= t + _EPS * (scale + abs(b)):
            continue
        ux, uy = _deepest(rows, i, lo0, lo1, hi0, hi1, scale, ux, uy)
        t = rows[i, 0] * ux + rows[i, 1] * uy - b
    return max_violation(ux, uy, rows, nrows), ux, uy


@njit(cache=True, inline="always")
def max_violation(ux, uy, rows, nrows):
    """The largest violation ``a_k u - b_k`` of ``rows[:nrows]`` at ``(ux, uy)``."""
    worst = -np.inf
    for k in range(nrows):
        worst = max(worst, rows[k, 0] * ux + rows[k, 1] * uy - rows[k, 2])
    return worst
