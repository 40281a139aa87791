"""The dense single-integrator filter in one compiled pass, for scenes of few agents.

For every agent of every env: its row against every other agent of the env (paper, eq. ``qp``,
with ``barriers.single_integrator_row``), exact culling (``barriers.support`` over the box,
``projection_disk.disk_support`` over the disk the solution lies in), and the exact
solve (``exact.solve_rows``). The same arithmetic, rows in the same order, as the general path
(pairs, packing, batched solve), without its intermediate arrays: bit-identical results, tested.
"""

from __future__ import annotations

import warnings

import numpy as np
from numba import njit, prange
from numba.core.errors import NumbaPerformanceWarning
from numpy.typing import NDArray

from rsvo_env import threads
from rsvo_env.barriers import single_integrator_row, support
from rsvo_env.projection_disk import disk_support
from rsvo_env.solvers.exact import solve_rows

# Up to this many agents an env, examining every pair here costs less than the general path's
# pair search, row packing and batched solve (measured: benchmarks/dense_filter_speed.py).
MAX_AGENTS = 350


@njit(cache=True, inline="always")
def _one_env(
    e, x, nom, omega, gamma, radii, lo, hi, buf, rows, out, feasible, active, violation, n_rows,
    moved,
):  # fmt: skip
    n = x.shape[1]
    xs, ys, rs, h, margin, bs = buf
    for j in range(n):
        xs[j], ys[j], rs[j] = x[e, j, 0], x[e, j, 1], radii[e, j]
    min_h = np.inf
    for i in range(n):
        lo0, lo1, hi0, hi1 = lo[e, i, 0], lo[e, i, 1], hi[e, i, 0], hi[e, i, 1]
        xi, yi, ri = xs[i], ys[i], rs[i]
        ux, uy = nom[e, i, 0], nom[e, i, 1]
        s = np.sqrt(ux * ux + uy * uy)
        # First every neighbour's barrier value and by how much its row clears the box (it
        # can bind only where b < support), branch-free so that the loop vectorises; then the
        # few rows that can bind, in neighbour order, of those also only the rows that can
        # bind in the disk [0, nominal] while no row has b < 0 (rsvo_env.projection_disk).
        for j in range(n):
            R = ri + rs[j]
            w = omega[e, i, j]
            ax, ay, b, hj = single_integrator_row(xi, yi, xs[j], ys[j], w, gamma, R * R)
            h[j], bs[j] = hj, b
            margin[j] = b - support(ax, ay, lo0, lo1, hi0, hi1)
        h[i], margin[i], bs[i] = np.inf, 0.0, 0.0
        b_min = 0.0
        for j in range(n):
            min_h = min(min_h, h[j])
            b_min = min(b_min, bs[j])
        exempt = b_min < 0.0
        k = 0
        for j in range(n):
            if margin[j] < 0.0:
                R = ri + rs[j]
                ax, ay, b, _ = single_integrator_row(
                    xi, yi, xs[j], ys[j], omega[e, i, j], gamma, R * R
                )
                if not exempt and b >= disk_support(ax, ay, ux, uy, s):
                    continue
                norm = np.hypot(ax, ay)
                if norm > 0.0:
                    rows[k, 0], rows[k, 1], rows[k, 2] = ax / norm, ay / norm, b / norm
                else:
                    rows[k, 0], rows[k, 1], rows[k, 2] = 0.0, 0.0, b
                k += 1
        ok, act, vio = solve_rows(
            nom[e, i, 0], nom[e, i, 1], rows, k, lo0, lo1, hi0, hi1, out[e, i]
        )
        feasible[e, i], active[e, i], violation[e, i], n_rows[e, i] = ok, act, vio, k
        dx, dy = out[e, i, 0] - nom[e, i, 0], out[e, i, 1] - nom[e, i, 1]
        moved[e, i] = np.sqrt(dx * dx + dy * dy)
    return min_h


@njit(cache=True, inline="always")
def _buffers(n):
    """One env's positions (x, y), radii, barrier values, box margins and right sides, one
    slot an agent."""
    return np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)


# The serial kernel is compiled with parallel=True though it has no prange: numba's parallel
# pipeline gives the same loop about 20 % less time (4 x 256: 121 against 150 us a call, one
# thread; bit for bit the same results, tested), and with no parallel loop no thread is ever
# launched. numba warns at compilation that it found nothing to parallelise; that is the point,
# so filter_dense compiles it with that warning silenced.
@njit(cache=True, parallel=True)
def _serial(x, nom, omega, gamma, radii, lo, hi, out, feasible, active, violation, n_rows, min_h,
            moved):  # fmt: skip
    buf = _buffers(x.shape[1])
    rows = np.empty((max(x.shape[1] - 1, 1), 3))
    for e in range(x.shape[0]):
        min_h[e] = _one_env(
            e, x, nom, omega, gamma, radii, lo, hi, buf, rows, out, feasible, active, violation,
            n_rows, moved,
        )  # fmt: skip


@njit(cache=True, parallel=True)
def _parallel(x, nom, omega, gamma, radii, lo, hi, out, feasible, active, violation, n_rows, min_h,
              moved):  # fmt: skip
    for e in prange(x.shape[0]):
        buf = _buffers(x.shape[1])
        rows = np.empty((max(x.shape[1] - 1, 1), 3))
        min_h[e] = _one_env(
            e, x, nom, omega, gamma, radii, lo, hi, buf, rows, out, feasible, active, violation,
            n_rows, moved,
        )  # fmt: skip


@njit(cache=True)
def _outputs(E, n):
    """The arrays :func:`_serial` and :func:`_parallel` fill, allocated in one compiled call."""
    return (
        np.empty((E, n, 2)),
        np.empty((E, n), dtype=np.bool_),
        np.empty((E, n), dtype=np.int64),
        np.empty((E, n)),
        np.empty((E, n), dtype=np.int64),
        np.empty(E),
        np.empty((E, n)),
    )


def filter_dense(
    positions: NDArray[np.float64],
    nominal: NDArray[np.float64],
    omega: NDArray[np.float64],
    gamma: float,
    radii: NDArray[np.float64],
    lo: NDArray[np.float64],
    hi: NDArray[np.float64],
) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray, NDArray, NDArray]:
    """Safe single-integrator controls of E envs x N agents, every pair of an env examined.

    positions, nominal (E, N, 2); omega (E, N, N); radii (E, N) body radii (a pair is safe at
    ``r_i + r_j``); lo, hi (E, N, 2) each agent's box. Returns actions (E, N, 2), feasible,
    active row count, largest normalised violation, rows kept after culling (E, N), each env's
    smallest barrier value (E,), and the intervention |u_safe - u_nominal| (E, N).
    """
    E, n = positions.shape[:2]
    outputs = _outputs(E, n)
    # the choice made here, not in compiled code: a parallel kernel called from another
    # compiled function runs many times slower
    kernel = _parallel if threads.parallel(E * n) else _serial
    args = (
        np.ascontiguousarray(positions, dtype=np.float64),
        np.ascontiguousarray(nominal, dtype=np.float64),
        np.ascontiguousarray(omega, dtype=np.float64),
        float(gamma),
        np.ascontiguousarray(radii, dtype=np.float64).reshape(E, n),
        np.ascontiguousarray(lo, dtype=np.float64).reshape(E, n, 2),
        np.ascontiguousarray(hi, dtype=np.float64).reshape(E, n, 2),
        *outputs,
    )
    if kernel is _serial and not _serial.signatures:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", category=NumbaPerformanceWarning)
            kernel(*args)
    else:
        kernel(*args)
    return outputs
