"""Reference backend: one QP per agent through qpsolvers (clarabel by default).

Slow, general and independent of the exact solver, which is what makes it a reference. An
infeasible QP is answered like the exact backend does: the least-violation action of a linear
program (``min t`` s.t. ``a_k u - t |a_k| <= b_k``, u in the box, solved by HiGHS through SciPy),
then the projection of the nominal onto the rows shifted by that ``t``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import qpsolvers
from numpy.typing import NDArray
from scipy import sparse
from scipy.optimize import linprog

from rsvo_env.qp import exact
from rsvo_env.util.validation import shown

# Tight tolerances. At clarabel's defaults the answer differs from the exact one by ~3e-5; at
# 1e-10 still by ~2e-5 on degenerate instances (a constraint active with a zero multiplier, e.g.
# the nominal exactly on a row), where an interior-point error shrinks only as sqrt(tolerance).
SOLVER_OPTIONS: dict[str, dict[str, Any]] = {
    "clarabel": {
        "tol_gap_abs": 1e-13,
        "tol_gap_rel": 1e-13,
        "tol_feas": 1e-12,
        "tol_ktratio": 1e-9,
        "max_iter": 400,
    },
    "daqp": {},
    "osqp": {
        "eps_abs": 1e-9,
        "eps_rel": 1e-9,
        "max_iter": 100000,
        "verbose": False,
    },
}


def _osqp_quiet() -> dict[str, Any]:
    """osqp's polishing under its own version's name (1.0 renamed ``polish``, warning on the
    old one) and ``raise_error`` given (1.x warns that its default will change); a failure is
    read from the solution's status either way."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        major = int(version("osqp").split(".")[0])
    except (PackageNotFoundError, ValueError):
        return {}
    return {"polishing": True, "raise_error": False} if major >= 1 else {"polish": True}


SOLVER_OPTIONS["osqp"].update(_osqp_quiet())


CLARABEL_DEFAULTS: dict[str, Any] = {"max_iter": 400}


def available_solvers() -> list[str]:
    return list(qpsolvers.available_solvers)


def least_violation(
    A: NDArray, b: NDArray, lo: NDArray, hi: NDArray
) -> tuple[NDArray[np.float64], float]:
    """LP ``min_{u in box, t} t`` s.t. ``(a_k u - b_k)/|a_k| <= t``; returns (u, t)."""
    norms = np.linalg.norm(A, axis=1)
    norms = np.where(norms > 0, norms, 1.0)
    G = np.hstack([A / norms[:, None], -np.ones((len(b), 1))])
    res = linprog(
        c=[0.0, 0.0, 1.0],
        A_ub=G,
        b_ub=b / norms,
        bounds=[(lo[0], hi[0]), (lo[1], hi[1]), (None, None)],
        method="highs",
        # HiGHS's default tolerances (1e-7) leave its optimum 1e-7 above the exact one
        options={"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10},
    )
    if res.status != 0:  # pragma: no cover - a bounded LP over a box always has a solution
        raise RuntimeError(f"least-violation LP failed: {res.message}")
    return res.x[:2], float(res.x[2])


def _qp(
    nominal: NDArray,
    A: NDArray,
    b: NDArray,
    lo: NDArray,
    hi: NDArray,
    solver: str,
    options: dict[str, Any],
) -> NDArray[np.float64] | None:
    """One qpsolvers call; the solution, or None when the solver found none it vouches for.

    An interior-point solver may stop at "almost solved" on a polygon that is a single point
    (a row touching the box at a corner); such an answer is kept when it is feasible to 1e-9 of
    the box's extent.
    """
    # Unit normals: the same half-planes, better conditioned for the solver, and a residual
    # measured in distance (the units of the box), whatever the rows' scale.
    norms = np.linalg.norm(A, axis=1) if len(b) else np.zeros(0)
    if np.any((norms == 0) & (b < 0)):
        return None  # a zero row with a negative right side: nothing satisfies it
    keep = norms > 0
    A, b = A[keep] / norms[keep, None], b[keep] / norms[keep]
    variants = [(A, b)]
    if len(b) > 1:
        # Rows with the same unit normal (to 1e-12) are one half-plane, the tightest. Duplicates
        # can make an interior-point solver degenerate (clarabel runs out of iterations), and
        # some single rows stall it too, so each form is tried in turn.
        key = np.round(A, 12)
        order = np.lexsort((b, key[:, 1], key[:, 0]))
        first = np.ones(len(b), dtype=bool)
        first[1:] = np.any(key[order][1:] != key[order][:-1], axis=1)
        if not first.all():
            variants.append((A[order][first], b[order][first]))
    scale = float(max(np.max(np.abs(lo)), np.max(np.abs(hi))))
    for A_try, b_try in variants:
        P, G = 2.0 * np.eye(2), A_try if len(b_try) else None
        if solver not in qpsolvers.dense_solvers:
            # a sparse-only solver (osqp, ...) would otherwise warn on every call about converting
            P = sparse.csc_matrix(P)
            G = None if G is None else sparse.csc_matrix(G)
        problem = qpsolvers.Problem(
            P,
            -2.0 * np.asarray(nominal, dtype=np.float64),
            G,
            b_try if len(b_try) else None,
            lb=lo,
            ub=hi,
        )
        sol = qpsolvers.solve_problem(problem, solver, **options)
        x = sol.x
        if x is None or not np.all(np.isfinite(x)):
            continue
        residual = max(
            float(np.max(A @ x - b - 1e-9 * (scale + np.abs(b)), initial=0.0)),
            float(np.max(lo - x)),
            float(np.max(x - hi)),
        )
        almost = str(sol.extras.get("status", "")).endswith("AlmostSolved")
        if (sol.found or almost) and residual <= 1e-9:
            return np.asarray(x, dtype=np.float64)
    return None


def solve_one(
    nominal: NDArray,
    A: NDArray,
    b: NDArray,
    lo: NDArray,
    hi: NDArray,
    solver: str = "clarabel",
    **options: Any,
) -> tuple[NDArray[np.float64], bool, float]:
    """One QP ``min |u - nominal|^2`` s.t. ``lo <= u <= hi``, ``A u <= b``.

    Returns (u, feasible, largest normalised violation). Feasibility is the QP solver's when it
    vouches for a solution, and otherwise the LP's: a polygon that is non-empty to 1e-9 is
    feasible (solved again with that sliver of slack), an empty one gets the least-violation
    action.
    """
    opts = {**SOLVER_OPTIONS.get(solver, {}), **options}
    A = np.asarray(A, dtype=np.float64).reshape(-1, 2)
    b = np.asarray(b, dtype=np.float64).reshape(-1)
    # The backends' tolerances are absolute: hand them the problem in units of the box, with
    # unit row normals, whatever the user's units and the rows' scale (1e-150 to 1e150).
    unit = box_scale(lo, hi)
    x, feasible, t = _solve_unit(
        np.asarray(nominal, dtype=np.float64) / unit,
        *unit_rows(A, b, unit),
        lo / unit,
        hi / unit,
        solver,
        opts,
    )
    return x * unit, feasible, t * unit


def box_scale(lo: NDArray, hi: NDArray) -> float:
    """The box's largest bound: the problem's unit of length."""
    return float(max(np.max(np.abs(lo)), np.max(np.abs(hi))))


def unit_rows(A: NDArray, b: NDArray, unit: float) -> tuple[NDArray, NDArray]:
    """The rows ``A u <= b`` with unit normals and in units of ``unit`` (zero rows kept as they
    are); each row is divided by its largest entry first, so its norm cannot overflow."""
    big = np.max(np.abs(A), axis=1) if len(b) else np.zeros(0)
    safe = np.where(big > 0, big, 1.0)
    A1, b1 = A / safe[:, None], b / safe
    norms = np.linalg.norm(A1, axis=1)
    norms = np.where(big > 0, norms, 1.0)
    return A1 / norms[:, None], b1 / norms / unit


def _solve_unit(
    nominal: NDArray,
    A: NDArray,
    b: NDArray,
    lo: NDArray,
    hi: NDArray,
    solver: str,
    opts: dict[str, Any],
) -> tuple[NDArray[np.float64], bool, float]:
    """``solve_one`` of a problem already in units of its box, with unit rows."""
    x = _qp(nominal, A, b, lo, hi, solver, opts)
    if x is not None:
        return x, True, 0.0
    x_lp, t = least_violation(A, b, lo, hi)
    scale = float(max(np.max(np.abs(lo)), np.max(np.abs(hi))))
    feasible = t <= exact.FEASIBILITY_TOL * scale
    norms = np.linalg.norm(A, axis=1)
    # A sliver of slack keeps the shifted polygon non-empty for the interior-point solver; it
    # is kept tiny (relative to the box), since along a row nearly parallel to a box edge it
    # widens a single-point polygon into a strip much longer than itself.
    # The projection from another solver, never the LP's vertex passed off as one: clarabel at
    # tight tolerances, then at its defaults, which converge where many nearly parallel rows
    # stall the tight run at "almost solved" (its answer is still checked feasible to 1e-9).
    attempts = [(solver, opts)] + [
        ("clarabel", o)
        for o in (SOLVER_OPTIONS["clarabel"], CLARABEL_DEFAULTS)
        if (solver, opts) != ("clarabel", o)
    ]
    x = None
    for rel in (1e-12, 1e-10, 1e-9):
        slack = max(t, 0.0) + rel * (scale + abs(t))
        for name, o in attempts:
            x = _qp(nominal, A, b + slack * norms, lo, hi, name, o)
            if x is not None:
                break
        if x is not None:
            break
    if x is None:
        raise RuntimeError(
            f"reference solver {shown(solver)} (and clarabel) found no projection for nominal "
            f"{np.asarray(nominal).tolist()} (in units of the box) with {len(b)} rows; the "
            f"least violation is {t:.3g}"
        )
    return x, bool(feasible), 0.0 if feasible else t


def solve_batch(
    nominal: NDArray,
    A: NDArray,
    b: NDArray,
    mask: NDArray,
    lo: NDArray,
    hi: NDArray,
    solver: str = "clarabel",
    **options: Any,
) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.int64], NDArray[np.float64]]:
    """Same contract as ``rsvo_env.qp.exact.solve_batch``, one qpsolvers call a row."""
    n = nominal.shape[0]
    m = np.asarray(mask, dtype=bool).reshape(n, -1)
    offsets = np.concatenate([[0], np.cumsum(m.sum(axis=1))])
    A = np.asarray(A, dtype=np.float64).reshape(n, -1, 2)[m]
    b = np.asarray(b, dtype=np.float64).reshape(n, -1)[m]
    return solve_csr(nominal, A, b, offsets, lo, hi, solver, **options)


def solve_csr(
    nominal: NDArray,
    A: NDArray,
    b: NDArray,
    offsets: NDArray,
    lo: NDArray,
    hi: NDArray,
    solver: str = "clarabel",
    **options: Any,
) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.int64], NDArray[np.float64]]:
    """Same contract as ``rsvo_env.qp.exact.solve_csr``, one qpsolvers call a row."""
    n = nominal.shape[0]
    lo = np.broadcast_to(lo, (n, 2))
    hi = np.broadcast_to(hi, (n, 2))
    out = np.empty((n, 2))
    feasible = np.empty(n, dtype=bool)
    active = np.zeros(n, dtype=np.int64)
    violation = np.zeros(n)
    for i in range(n):  # the reference is one QP at a time by design
        Ai, bi = A[offsets[i] : offsets[i + 1]], b[offsets[i] : offsets[i + 1]]
        out[i], feasible[i], violation[i] = solve_one(
            nominal[i], Ai, bi, lo[i], hi[i], solver, **options
        )
        if len(bi):
            norms = np.maximum(np.linalg.norm(Ai, axis=1), 1e-300)
            slack = (Ai @ out[i] - bi) / norms
            active[i] = int(np.sum(np.abs(slack - violation[i]) <= 1e-7 * (1 + np.abs(bi))))
    return out, feasible, active, violation
