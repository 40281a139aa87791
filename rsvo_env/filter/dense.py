"""The dense single-integrator filter in one compiled pass, for scenes of few agents.

For every agent of every env: its row against every other agent of the env (paper, eq. ``qp``,
with ``single_integrator.single_integrator_row``), exact culling (``rows.support`` over the box,
``projection_disk.disk_support`` over the disk the solution lies in), and the exact
solve (``exact.solve_rows``). The same arithmetic, rows in the same order, as the general path
(pairs, packing, batched solve), without its intermediate arrays: bit-identical results, tested.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from rsvo_env.dynamics.single_integrator import single_integrator_row
from rsvo_env.filter.projection_disk import disk_support
from rsvo_env.filter.result import FilterResult
from rsvo_env.qp.exact import solve_rows
from rsvo_env.qp.rows import support
from rsvo_env.util import threads

# Up to this many agents an env the compiled all-pairs pass serves (rsvo_env.util.sizes).


@njit(cache=True, inline="always")
def _one_env(
    e,
    x,
    nom,
    omega,
    gamma,
    radii,
    lo,
    hi,
    rows,
    in_disk,
    out,
    feasible,
    active,
    violation,
    n_rows,
    moved,
):
    n = x.shape[1]
    min_h = np.inf
    for i in range(n):
        a = e * n + i  # the bodies' flat index
        lo0, lo1, hi0, hi1 = lo[a, 0], lo[a, 1], hi[a, 0], hi[a, 1]
        xi, yi, ri = x[e, i, 0], x[e, i, 1], radii[a]
        ux, uy = nom[e, i, 0], nom[e, i, 1]
        s = np.sqrt(ux * ux + uy * uy)
        # One pass over the neighbours: the rows that can bind in the box (b < support), in
        # neighbour order, each marked if it can also bind in the disk [0, nominal]; then, if
        # no row has b < 0 (the agent is not exempt, rsvo_env.filter.projection_disk), only the
        # marked ones are kept: one pass costs less than a branch-free first pass over copies of
        # the positions and a second (benchmarks/results/dense_filter_speed.md).
        k = 0
        b_min = 0.0
        for j in range(n):
            if j == i:
                continue
            R = ri + radii[e * n + j]
            ax, ay, b, h = single_integrator_row(
                xi, yi, x[e, j, 0], x[e, j, 1], omega[e, i, j], gamma, R * R
            )
            min_h = min(min_h, h)
            b_min = min(b_min, b)
            if b < support(ax, ay, lo0, lo1, hi0, hi1):
                in_disk[k] = b < disk_support(ax, ay, ux, uy, s)
                norm = np.hypot(ax, ay)
                if norm > 0.0:
                    rows[k, 0], rows[k, 1], rows[k, 2] = ax / norm, ay / norm, b / norm
                else:
                    rows[k, 0], rows[k, 1], rows[k, 2] = 0.0, 0.0, b
                k += 1
        if b_min >= 0.0:
            kept = 0
            for r in range(k):
                if in_disk[r]:
                    rows[kept, 0], rows[kept, 1], rows[kept, 2] = rows[r, 0], rows[r, 1], rows[r, 2]
                    kept += 1
            k = kept
        ok, act, vio = solve_rows(ux, uy, rows, k, lo0, lo1, hi0, hi1, out[e, i])
        feasible[e, i], active[e, i], violation[e, i], n_rows[e, i] = ok, act, vio, k
        dx, dy = out[e, i, 0] - ux, out[e, i, 1] - uy
        moved[e, i] = np.sqrt(dx * dx + dy * dy)
    return min_h


@njit(cache=True, inline="always")
def _scratch(n):
    """One env's rows (at most one a neighbour) and their disk flags."""
    m = max(n - 1, 1)
    return np.empty((m, 3)), np.empty(m, dtype=np.bool_)


Outputs = tuple[NDArray, NDArray, NDArray, NDArray, NDArray, NDArray, NDArray]


def _outputs(E: int, n: int) -> Outputs:
    """The arrays ``_serial`` and ``_parallel`` fill: allocated here, as a compiled
    function's returned arrays cost more each to hand back to Python (measured at 6 agents)."""
    return (
        np.empty((E, n, 2)),
        np.empty((E, n), dtype=np.bool_),
        np.empty((E, n), dtype=np.int64),
        np.empty((E, n)),
        np.empty((E, n), dtype=np.int64),
        np.empty(E),
        np.empty((E, n)),
    )


@njit(cache=True)
def _serial(
    x, nom, omega, gamma, radii, lo, hi, out, feasible, active, violation, n_rows, min_h, moved
):
    rows, in_disk = _scratch(x.shape[1])
    for e in range(x.shape[0]):
        min_h[e] = _one_env(
            e,
            x,
            nom,
            omega,
            gamma,
            radii,
            lo,
            hi,
            rows,
            in_disk,
            out,
            feasible,
            active,
            violation,
            n_rows,
            moved,
        )


@njit(cache=True, parallel=True)
def _parallel(
    x, nom, omega, gamma, radii, lo, hi, out, feasible, active, violation, n_rows, min_h, moved
):
    for e in prange(x.shape[0]):
        rows, in_disk = _scratch(x.shape[1])
        min_h[e] = _one_env(
            e,
            x,
            nom,
            omega,
            gamma,
            radii,
            lo,
            hi,
            rows,
            in_disk,
            out,
            feasible,
            active,
            violation,
            n_rows,
            moved,
        )


def _flat(a: NDArray, shape: tuple[int, ...]) -> NDArray[np.float64]:
    """``a`` as contiguous floats of ``shape``: the bodies' own arrays have it already."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    return a if a.shape == shape else a.reshape(shape)


def filter_dense(
    positions: NDArray[np.float64],
    nominal: NDArray[np.float64],
    omega: NDArray[np.float64],
    gamma: float,
    radii: NDArray[np.float64],
    lo: NDArray[np.float64],
    hi: NDArray[np.float64],
) -> Outputs:
    """Safe single-integrator controls of E envs x N agents, every pair of an env examined.

    positions, nominal (E, N, 2); omega (E, N, N); radii (E, N) body radii (a pair is safe at
    ``r_i + r_j``); lo, hi (E, N, 2) each agent's box (the bodies' flat (E N,) and (E N, 2)
    serve as well). Returns actions (E, N, 2), feasible, active row count, largest normalised
    violation, rows kept after culling (E, N), each env's smallest barrier value (E,), and the
    intervention |u_safe - u_nominal| (E, N).
    """
    E, n = positions.shape[:2]
    outputs = _outputs(E, n)
    args = (
        np.ascontiguousarray(positions, dtype=np.float64),
        np.ascontiguousarray(nominal, dtype=np.float64),
        np.ascontiguousarray(omega, dtype=np.float64),
        float(gamma),
        _flat(radii, (E * n,)),
        _flat(lo, (E * n, 2)),
        _flat(hi, (E * n, 2)),
        *outputs,
    )
    # the form chosen here, not in compiled code: a parallel kernel called from another
    # compiled function runs many times slower
    threads.launch(_serial, _parallel, E * n, *args)
    return outputs


def dense_result(
    cfg: Any, positions: NDArray, nominal: NDArray, omega: NDArray, bodies: Any
) -> FilterResult:
    """The compiled all-pairs pass (``filter_dense``) as a ``FilterResult``: ``positions``
    and ``nominal`` (E, N, 2), ``omega`` (E, N, N), the filter's config ``cfg`` and each
    agent's ``bodies``; no rows kept (none is built)."""
    actions, feasible, active, violation, n_rows, min_h, intervention = filter_dense(
        positions, nominal, omega, cfg.gamma, bodies.radii, bodies.lo, bodies.hi
    )
    zeros = np.zeros(len(min_h), dtype=np.int64)
    return FilterResult(
        actions=actions,
        feasible=feasible,
        intervention=intervention,
        active=active,
        min_h=min_h,
        max_violation=violation,
        n_rows=n_rows,
        n_unrecoverable_pairs=zeros,
        n_capped_shares=zeros,
    )
