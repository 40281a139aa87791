"""Batched exact projection onto a box intersected with half-planes, in 2-D (numba).

Each problem is the paper's QP (eq. ``qp``): ``min |u - u_nom|^2`` s.t. ``lo <= u <= hi`` and
``A u <= b``. In two dimensions it is solved exactly by the incremental algorithm of ORCA's
``linearProgram2`` (van den Berg et al.): start at the box projection of the nominal, add the rows
one by one, and when a row is violated re-solve on that row's line, a 1-D problem bounded by the
box and the rows before it. Seidel's argument makes this exact: if the optimum of the first k
rows violates row k, the optimum of the first k+1 rows lies on row k's line.

Every round-off allowance is relative to the problem's scale (the box's extent and the rows'
offsets). An empty polygon (one that stays empty when every row is moved out by
``FEASIBILITY_TOL`` times the box's extent) is reported (``feasible=False``) and replaced by
the action that minimises the largest normalised violation ``max_k (a_k u - b_k)/|a_k|`` over
the box, and among those the one closest to the nominal (the role of ORCA's
``linearProgram3``): the min-max value ``t`` by Seidel's incremental linear program
(``rsvo_env.qp.least_violation``), then the exact projection onto the rows shifted by ``t``.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from rsvo_env.qp import least_violation
from rsvo_env.util import threads

# Round-off allowances, relative to the problem's scale: a row whose offset is b (unit normal) is
# satisfied to _EPS * (scale + |b|), with ``scale`` the box's extent, so a user in millimetres
# gets the same answers as one in metres.
_EPS = 1e-12
_ACTIVE_TOL = 1e-9
# A polygon that a shift of every row by FEASIBILITY_TOL * scale makes non-empty is feasible:
# round-off in h (agents resting exactly at the safety distance) is not infeasibility.
FEASIBILITY_TOL = 1e-9


@njit(cache=True, inline="always")
def _narrow(lo, hi, bound, upper):
    """The interval [lo, hi] cut by ``t <= bound`` (upper) or ``t >= bound``."""
    if upper:
        return lo, min(hi, bound)
    return max(lo, bound), hi


@njit(cache=True, inline="always")
def _project(nx, ny, rows, nrows, shift, lo0, lo1, hi0, hi1, scale):
    """Exact projection of (nx, ny) onto box ∩ {rows[k,:2]·u <= rows[k,2] + shift}.

    ``rows`` are normalised (unit normal). Returns (ux, uy, feasible). On each row's line the
    algorithm keeps two intervals: the exact one, where the point goes, and one widened by the
    round-off allowances (see ``_EPS``), which decides feasibility. When only rounding empties
    the exact interval (a polygon that is a single point, e.g. a row through a box corner), the
    point is the middle of its bounds: no allowance lets it slide along a nearly parallel edge.
    Nearly parallel lines need no threshold: their crossing, however far, is computed.
    """
    ux = min(max(nx, lo0), hi0)
    uy = min(max(ny, lo1), hi1)
    for k in range(nrows):
        ax = rows[k, 0]
        ay = rows[k, 1]
        bk = rows[k, 2] + shift
        tol = _EPS * (scale + abs(bk))
        if ax == 0.0 and ay == 0.0:
            if bk < -tol:
                return ux, uy, False
            continue
        if ax * ux + ay * uy <= bk + tol:
            continue
        # The new optimum lies on the line ax*x + ay*y = bk: p0 + t*d.
        p0x = bk * ax
        p0y = bk * ay
        dx = -ay
        dy = ax
        t = dx * (nx - p0x) + dy * (ny - p0y)
        elo, ehi = -np.inf, np.inf  # exact
        wlo, whi = -np.inf, np.inf  # widened
        for p0c, dc, lc, hc in ((p0x, dx, lo0, hi0), (p0y, dy, lo1, hi1)):
            if dc != 0.0:
                t1, t2 = (lc - p0c) / dc, (hc - p0c) / dc
                elo, ehi = max(elo, min(t1, t2)), min(ehi, max(t1, t2))
                t1, t2 = (lc - tol - p0c) / dc, (hc + tol - p0c) / dc
                wlo, whi = max(wlo, min(t1, t2)), min(whi, max(t1, t2))
            elif p0c < lc - tol or p0c > hc + tol:
                return ux, uy, False
        for m in range(k):
            amx = rows[m, 0]
            amy = rows[m, 1]
            if amx == 0.0 and amy == 0.0:
                continue
            bm = rows[m, 2] + shift
            denom = amx * dx + amy * dy
            numer = bm - (amx * p0x + amy * p0y)
            allowance = _EPS * (scale + abs(bm))
            if denom == 0.0:
                # Parallel to row k: all of line k satisfies row m, or none of it does.
                if numer + allowance < 0.0:
                    return ux, uy, False
                continue
            elo, ehi = _narrow(elo, ehi, numer / denom, denom > 0.0)
            wlo, whi = _narrow(wlo, whi, (numer + allowance) / denom, denom > 0.0)
        if wlo > whi:
            return ux, uy, False
        if elo <= ehi:
            t = min(max(t, elo), ehi)
        else:
            t = min(max(0.5 * (elo + ehi), wlo), whi)
        ux = p0x + t * dx
        uy = p0y + t * dy
    return ux, uy, True


@njit(cache=True, inline="always")
def set_row(rows, k, ax, ay, b):
    """Store row k normalised to a unit normal (a zero row keeps its right side)."""
    norm = np.hypot(ax, ay)
    if norm > 0.0:
        rows[k, 0] = ax / norm
        rows[k, 1] = ay / norm
        rows[k, 2] = b / norm
    else:
        rows[k, 0] = 0.0
        rows[k, 1] = 0.0
        rows[k, 2] = b


@njit(cache=True)
def _solve_one(nom, A, b, mask, lo, hi, rows, out):
    """One QP; ``rows`` is scratch space. Returns (feasible, active, max_violation)."""
    nrows = 0
    for k in range(A.shape[0]):
        if mask[k]:
            set_row(rows, nrows, A[k, 0], A[k, 1], b[k])
            nrows += 1
    return solve_rows(nom[0], nom[1], rows, nrows, lo[0], lo[1], hi[0], hi[1], out)


@njit(cache=True)
def solve_rows(nx, ny, rows, nrows, lo0, lo1, hi0, hi1, out):
    """The QP of normalised ``rows[:nrows]``; writes the action to ``out``. Returns
    (feasible, active, max_violation)."""
    ok, violation = solve_point(nx, ny, rows, nrows, lo0, lo1, hi0, hi1, out)
    scale = max(max(abs(lo0), abs(hi0)), max(abs(lo1), abs(hi1)))
    ux, uy = out[0], out[1]
    active = 0
    for k in range(nrows):
        if abs(rows[k, 0] * ux + rows[k, 1] * uy - rows[k, 2]) <= _ACTIVE_TOL * (
            scale + abs(rows[k, 2])
        ):
            active += 1
    return ok, active, violation


@njit(cache=True)
def solve_point(nx, ny, rows, nrows, lo0, lo1, hi0, hi1, out):
    """``solve_rows`` without counting the active rows: (feasible, max_violation)."""
    scale = max(max(abs(lo0), abs(hi0)), max(abs(lo1), abs(hi1)))
    ux, uy, ok = _project(nx, ny, rows, nrows, 0.0, lo0, lo1, hi0, hi1, scale)
    violation = 0.0
    if not ok:
        # Least violation: the smallest shift t of every row that makes the polygon non-empty
        # (rsvo_env.qp.least_violation), then the point of that polygon closest to the nominal;
        # the program's own point where rounding leaves the polygon empty or a single point
        bx = min(max(nx, lo0), hi0)
        by = min(max(ny, lo1), hi1)
        t, lx, ly = least_violation.min_max(rows, nrows, lo0, lo1, hi0, hi1, scale, bx, by)
        ux, uy, feas = _project(nx, ny, rows, nrows, max(t, 0.0), lo0, lo1, hi0, hi1, scale)
        violation = least_violation.max_violation(ux, uy, rows, nrows) if feas else np.inf
        if violation > t + FEASIBILITY_TOL * scale:
            ux, uy, violation = lx, ly, t
        violation = max(violation, 0.0)
        if violation <= FEASIBILITY_TOL * scale:
            ok = True
            violation = 0.0
    # The input bounds are physical limits: never exceed them, not even by a rounding.
    ux = min(max(ux, lo0), hi0)
    uy = min(max(uy, lo1), hi1)
    out[0] = ux
    out[1] = uy
    return ok, violation


@njit(cache=True)
def _solve_serial(nominal, A, b, mask, lo, hi, out, feasible, active, violation):
    rows = np.empty((A.shape[1], 3))
    for i in range(nominal.shape[0]):
        ok, act, vio = _solve_one(nominal[i], A[i], b[i], mask[i], lo[i], hi[i], rows, out[i])
        feasible[i] = ok
        active[i] = act
        violation[i] = vio


@njit(cache=True, parallel=True)
def _solve_parallel(nominal, A, b, mask, lo, hi, out, feasible, active, violation):
    n = nominal.shape[0]
    chunk = 64
    for c in prange((n + chunk - 1) // chunk):
        rows = np.empty((A.shape[1], 3))
        for i in range(c * chunk, min(n, (c + 1) * chunk)):
            ok, act, vio = _solve_one(nominal[i], A[i], b[i], mask[i], lo[i], hi[i], rows, out[i])
            feasible[i] = ok
            active[i] = act
            violation[i] = vio


@njit(cache=True)
def _solve_csr_one(i, nominal, A, b, offsets, lo, hi, rows, out, feasible, active, violation):
    nrows = 0
    for k in range(offsets[i], offsets[i + 1]):
        set_row(rows, nrows, A[k, 0], A[k, 1], b[k])
        nrows += 1
    nom = nominal[i]
    ok, act, vio = solve_rows(
        nom[0], nom[1], rows, nrows, lo[i, 0], lo[i, 1], hi[i, 0], hi[i, 1], out[i]
    )
    feasible[i] = ok
    active[i] = act
    violation[i] = vio


@njit(cache=True)
def _widest(offsets):
    K = 1
    for i in range(offsets.shape[0] - 1):
        K = max(K, offsets[i + 1] - offsets[i])
    return K


@njit(cache=True)
def _solve_csr_serial(nominal, A, b, offsets, lo, hi, out, feasible, active, violation):
    rows = np.empty((_widest(offsets), 3))
    for i in range(nominal.shape[0]):
        _solve_csr_one(i, nominal, A, b, offsets, lo, hi, rows, out, feasible, active, violation)


@njit(cache=True, parallel=True)
def _solve_csr_parallel(nominal, A, b, offsets, lo, hi, out, feasible, active, violation):
    n = nominal.shape[0]
    chunk = 64
    K = _widest(offsets)
    for c in prange((n + chunk - 1) // chunk):
        rows = np.empty((K, 3))
        for i in range(c * chunk, min(n, (c + 1) * chunk)):
            _solve_csr_one(
                i, nominal, A, b, offsets, lo, hi, rows, out, feasible, active, violation
            )


def solve_csr(
    nominal: NDArray[np.float64],
    A: NDArray[np.float64],
    b: NDArray[np.float64],
    offsets: NDArray[np.int64],
    lo: NDArray[np.float64],
    hi: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.int64], NDArray[np.float64]]:
    """``solve_batch`` of rows stored by agent (``rsvo_env.qp.rows.Rows``): QP i has the
    rows ``A[offsets[i]:offsets[i + 1]]`` (R, 2), ``b`` (R,); the scratch space is the widest
    agent's, once per thread, so memory follows the rows, not n times the widest."""
    nominal, lo, hi, outputs = _batch(nominal, lo, hi)
    threads.launch(
        _solve_csr_serial,
        _solve_csr_parallel,
        len(nominal),
        nominal,
        np.ascontiguousarray(A, dtype=np.float64).reshape(-1, 2),
        np.ascontiguousarray(b, dtype=np.float64),
        np.ascontiguousarray(offsets, dtype=np.int64),
        lo,
        hi,
        *outputs,
    )
    return outputs


def _batch(nominal: NDArray, lo: NDArray, hi: NDArray) -> tuple[NDArray, NDArray, NDArray, tuple]:
    """The kernels' inputs as contiguous float arrays, a box per problem, and their outputs
    (actions, feasible, active, violation), allocated."""
    nominal = np.ascontiguousarray(nominal, dtype=np.float64)
    n = nominal.shape[0]
    lo = np.ascontiguousarray(np.broadcast_to(lo, (n, 2)), dtype=np.float64)
    hi = np.ascontiguousarray(np.broadcast_to(hi, (n, 2)), dtype=np.float64)
    outputs = (np.empty((n, 2)), np.empty(n, np.bool_), np.empty(n, np.int64), np.empty(n))
    return nominal, lo, hi, outputs


def solve_batch(
    nominal: NDArray[np.float64],
    A: NDArray[np.float64],
    b: NDArray[np.float64],
    mask: NDArray[np.bool_],
    lo: NDArray[np.float64],
    hi: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.int64], NDArray[np.float64]]:
    """Solve B independent 2-D QPs exactly.

    Shapes: nominal (B, 2), A (B, K, 2), b (B, K), mask (B, K), lo and hi (B, 2) or (2,).
    Returns actions (B, 2), feasible (B,), active row count (B,), and the largest normalised
    violation (B,) (0 where feasible).
    """
    nominal, lo, hi, outputs = _batch(nominal, lo, hi)
    n = nominal.shape[0]
    A = np.ascontiguousarray(A, dtype=np.float64).reshape(n, -1, 2)
    b = np.ascontiguousarray(b, dtype=np.float64).reshape(n, -1)
    mask = np.ascontiguousarray(mask, dtype=np.bool_).reshape(n, -1)
    if A.shape[1] == 0:
        A = np.zeros((n, 1, 2))
        b = np.zeros((n, 1))
        mask = np.zeros((n, 1), dtype=np.bool_)
    threads.launch(_solve_serial, _solve_parallel, n, nominal, A, b, mask, lo, hi, *outputs)
    return outputs
