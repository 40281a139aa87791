"""Uniform-grid neighbour search in the plane, compiled: the pairs within per-agent radii and
each agent's nearest distance, env by env (pairs never cross envs), O(N) work for a crowd of
bounded density instead of a KD-tree's Python-level result lists.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray


@njit(cache=True)
def build_cells(x, cell):
    """Cells of side ``cell`` over the points' bounding box (coarsened so there are at most
    about 4 cells a point): (origin, cell, nx, ny, start, order) with the points of cell c at
    ``order[start[c]:start[c + 1]]``, in index order."""
    n = x.shape[0]
    lo0, lo1 = x[:, 0].min(), x[:, 1].min()
    span0, span1 = x[:, 0].max() - lo0, x[:, 1].max() - lo1
    if not cell > 0.0:
        cell = max(span0, span1, 1.0)
    while (span0 / cell + 1.0) * (span1 / cell + 1.0) > 4.0 * n + 64.0:
        cell *= 2.0
    nx, ny = int(span0 / cell) + 1, int(span1 / cell) + 1
    cid = np.empty(n, dtype=np.int64)
    start = np.zeros(nx * ny + 1, dtype=np.int64)
    for i in range(n):
        c = min(int((x[i, 0] - lo0) / cell), nx - 1) * ny + min(int((x[i, 1] - lo1) / cell), ny - 1)
        cid[i] = c
        start[c + 1] += 1
    for c in range(nx * ny):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    order = np.empty(n, dtype=np.int64)
    for i in range(n):
        order[fill[cid[i]]] = i
        fill[cid[i]] += 1
    return lo0, lo1, cell, nx, ny, start, order


@njit(cache=True)
def cell_span(v, r, lo, cell, m):
    """Cell range [a, b] covering [v - r, v + r] along one axis of m cells (r may be huge)."""
    a = min(max((v - r - lo) / cell, 0.0), m - 1.0)
    b = min(max((v + r - lo) / cell, 0.0), m - 1.0)
    return int(a), int(b)


@njit(cache=True, inline="always")
def _may_bind(dx, dy, d2, ux, uy, s, a, R):
    """Whether a row ``2 yᵀu <= a (|y|^2 - R^2)`` (y = (dx, dy) the neighbour's offset,
    ``d2 = |y|^2``) can bind within the disk with diameter [0, u] (``s = |u|``,
    ``rsvo_env.filter.projection_disk``): ``a (d2 - R^2) - yᵀu < |y| s``, widened by 1e-9 as the
    disk's support is there, without a square root."""
    lhs = a * (d2 - R * R) - (dx * ux + dy * uy)
    return lhs < 0.0 or lhs * lhs < d2 * (s * s) * (1.0 + 2e-9)


@njit(cache=True)
def _pairs(x, radius, group, cell, nominal, scaled_floor, reach, boxed):
    """Flat pair keys ``e * n + i``, ``e * n + j`` (i < j) of agents closer than the larger of
    ``radius[i, group[j]]`` and ``radius[j, group[i]]``, each pair once: agent i scans group
    g's grid within ``radius[i, g]``, and a pair is kept from the scan of the agent with the
    larger radius against the other's group (the lower index on a tie), the one scan sure to
    find it. So agent i skips group g when every member's radius against i's group exceeds
    its own: each pair it could find, the member keeps. With ``nominal`` (E, N, 2) (else
    empty), a pair is kept only where a side's row can bind within its disk [0, nominal]
    (``_may_bind``, weight times gamma ``scaled_floor`` (E, N, K), safe distance
    ``reach`` (E, N)) or the side is ``boxed`` (E, N: its rows are all kept): the owning
    scan tests both sides."""
    E, n, K = radius.shape
    disk = nominal.shape[0] > 0
    cap = max(16, 8 * E * n)
    I = np.empty(cap, dtype=np.int64)
    J = np.empty(cap, dtype=np.int64)
    m = 0
    for e in range(E):
        xe, re, ge = x[e], radius[e], group[e]
        # smallest[g, h]: the smallest radius of a member of group g against group h
        smallest = np.full((K, K), np.inf)
        for j in range(n):
            for h in range(K):
                smallest[ge[j], h] = min(smallest[ge[j], h], re[j, h])
        for g in range(K):
            members = np.nonzero(ge == g)[0]
            if members.shape[0] == 0:
                continue
            lo0, lo1, c, nx, ny, start, order = build_cells(xe[members], cell[e, g])
            # the group's agents in cell order, so a cell's scan reads contiguous memory
            idx = members[order]
            px, py, rr = xe[idx, 0].copy(), xe[idx, 1].copy(), re[idx].copy()
            if disk:
                ux, uy = nominal[e, idx, 0].copy(), nominal[e, idx, 1].copy()
                us = np.sqrt(ux * ux + uy * uy)
                aa, RR, bx = scaled_floor[e, idx].copy(), reach[e, idx].copy(), boxed[e, idx].copy()
            for i in range(n):
                ri = re[i, g]
                gi = ge[i]
                if not ri > 0.0 or smallest[g, gi] > ri:
                    continue
                if disk:
                    uxi, uyi = nominal[e, i, 0], nominal[e, i, 1]
                    si, ai, Ri = np.sqrt(uxi * uxi + uyi * uyi), scaled_floor[e, i, g], reach[e, i]
                r2 = ri * ri
                a0, b0 = cell_span(xe[i, 0], ri, lo0, c, nx)
                a1, b1 = cell_span(xe[i, 1], ri, lo1, c, ny)
                for gx in range(a0, b0 + 1):
                    # cells a1..b1 of a column are consecutive: their agents are one run
                    for s in range(start[gx * ny + a1], start[gx * ny + b1 + 1]):
                        j = idx[s]
                        if j == i:
                            continue
                        dx, dy = xe[i, 0] - px[s], xe[i, 1] - py[s]
                        d2 = dx * dx + dy * dy
                        rj = rr[s, gi]
                        if d2 > r2 or (d2 <= rj * rj and (rj > ri or (rj == ri and j < i))):
                            continue  # beyond i's radius, or j's scan keeps it
                        if disk and not (
                            boxed[e, i]
                            or _may_bind(-dx, -dy, d2, uxi, uyi, si, ai, Ri)
                            or (
                                d2 <= rj * rj
                                and (
                                    bx[s]
                                    or _may_bind(dx, dy, d2, ux[s], uy[s], us[s], aa[s, gi], RR[s])
                                )
                            )
                        ):
                            continue  # neither row can bind
                        if m == cap:
                            cap *= 2
                            I2 = np.empty(cap, dtype=np.int64)
                            J2 = np.empty(cap, dtype=np.int64)
                            I2[:m], J2[:m] = I[:m], J[:m]
                            I, J = I2, J2
                        I[m] = e * n + min(i, j)
                        J[m] = e * n + max(i, j)
                        m += 1
    return I[:m], J[:m]


@njit(cache=True)
def _sorted(I, J, m):
    """Pairs in (I, J) order: a counting sort by I, then each agent's few J by insertion."""
    start = np.zeros(m + 1, dtype=np.int64)
    for p in range(I.shape[0]):
        start[I[p] + 1] += 1
    for a in range(m):
        start[a + 1] += start[a]
    fill = start[:-1].copy()
    I2, J2 = np.empty_like(I), np.empty_like(J)
    for p in range(I.shape[0]):
        q = fill[I[p]]
        I2[q], J2[q] = I[p], J[p]
        fill[I[p]] += 1
    for a in range(m):
        if start[a + 1] - start[a] > 16:
            J2[start[a] : start[a + 1]] = np.sort(J2[start[a] : start[a + 1]])
            continue
        for q in range(start[a] + 1, start[a + 1]):
            v = J2[q]
            k = q
            while k > start[a] and J2[k - 1] > v:
                J2[k] = J2[k - 1]
                k -= 1
            J2[k] = v
    return I2, J2


@njit(cache=True)
def _scan_cell(xe, i, g, start, order, best):
    for s in range(start[g], start[g + 1]):
        j = order[s]
        if j != i:
            dx, dy = xe[i, 0] - xe[j, 0], xe[i, 1] - xe[j, 1]
            best = min(best, dx * dx + dy * dy)
    return best


@njit(cache=True)
def _nearest(x, out):
    """Each agent's distance to its nearest other agent, by rings of cells around its own: after
    ring k every unscanned agent is at least k cells away."""
    E, n = x.shape[0], x.shape[1]
    for e in range(E):
        xe = x[e]
        span0 = xe[:, 0].max() - xe[:, 0].min()
        span1 = xe[:, 1].max() - xe[:, 1].min()
        cell = max(np.sqrt(span0 * span1 / n), max(span0, span1) / n, 1e-300)
        lo0, lo1, c, nx, ny, start, order = build_cells(xe, cell)
        for i in range(n):
            gx0 = min(int((xe[i, 0] - lo0) / c), nx - 1)
            gy0 = min(int((xe[i, 1] - lo1) / c), ny - 1)
            best = np.inf
            k = 0
            while True:
                for gx in range(max(gx0 - k, 0), min(gx0 + k, nx - 1) + 1):
                    if gx == gx0 - k or gx == gx0 + k:
                        for gy in range(max(gy0 - k, 0), min(gy0 + k, ny - 1) + 1):
                            best = _scan_cell(xe, i, gx * ny + gy, start, order, best)
                    else:
                        if gy0 - k >= 0:
                            best = _scan_cell(xe, i, gx * ny + gy0 - k, start, order, best)
                        if gy0 + k < ny:
                            best = _scan_cell(xe, i, gx * ny + gy0 + k, start, order, best)
                if best <= (k * c) ** 2 or k > max(nx, ny):
                    break
                k += 1
            out[e, i] = np.sqrt(best)


@njit(cache=True)
def _mean_radii(r):
    """(E, K) the mean positive finite radius against each group (1 where there is none)."""
    E, n, K = r.shape
    total = np.zeros((E, K))
    count = np.zeros((E, K))
    for e in range(E):
        for i in range(n):
            for k in range(K):
                v = r[e, i, k]
                if v > 0.0 and np.isfinite(v):
                    total[e, k] += v
                    count[e, k] += 1.0
    return np.where(count > 0, total / np.maximum(count, 1.0), 1.0)


def pairs_within_radii(
    positions: NDArray[np.float64],
    radius: NDArray[np.float64],
    group: NDArray[np.int64] | None = None,
    disk: tuple[NDArray, NDArray, NDArray, NDArray] | None = None,
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Pairs (I < J, flat indices ``e * N + i``, sorted) of agents of the same env closer than
    the larger of their two radii. ``positions`` (E, N, 2); ``radius`` (E, N), or (E, N, K)
    with ``group`` (E, N) labels in [0, K): agent i's radius against the agents of group g is
    ``radius[e, i, g]`` (>= 0; with radius 0 an agent searches nothing). Each group gets a
    grid of cells the mean radius against it. ``disk``: (nominal (E, N, 2), weight floor
    times gamma (E, N, K), safe distance (E, N), boxed (E, N)), to keep only the pairs with a
    row that can bind within its agent's disk [0, nominal] (``rsvo_env.filter.projection_disk``) or
    of a boxed agent."""
    x = np.ascontiguousarray(positions, dtype=np.float64)
    r = np.asarray(radius, dtype=np.float64)
    if r.ndim == 2:
        r = r[..., None]
    r = np.ascontiguousarray(r)
    if group is None:
        group = np.zeros(x.shape[:2], dtype=np.int64)
    # the mean positive finite radius against each group (a median costs more than it saves);
    # an agent with an infinite radius scans every cell whatever their size
    cell = _mean_radii(r)
    if disk is None:
        disk = (
            np.zeros((0, 0, 2)),
            np.zeros((0, 0, 0)),
            np.zeros((0, 0)),
            np.zeros((0, 0), dtype=np.bool_),
        )
    *floats, boxed = disk
    floats = [np.ascontiguousarray(a, dtype=np.float64) for a in floats]
    I, J = _pairs(
        x,
        r,
        np.ascontiguousarray(group, dtype=np.int64),
        cell,
        *floats,
        np.ascontiguousarray(boxed, dtype=np.bool_),
    )
    return _sorted(I, J, x.shape[0] * x.shape[1])


def nearest_distance(positions: NDArray[np.float64]) -> NDArray[np.float64]:
    """(E, N) distance from each agent to the nearest other agent of its env (inf when alone)."""
    x = np.ascontiguousarray(positions, dtype=np.float64)
    out = np.empty(x.shape[:2])
    _nearest(x, out)
    return out
