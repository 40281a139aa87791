"""Nearest-neighbour queries over agent positions, batch-first: (E, N, 2) or (N, 2).

Dense for few agents, one KD-tree over all envs for many. Pairs never cross envs: in the tree each
env is shifted along x by more than any distance inside an env, and distances are recomputed from
the unshifted positions.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from rsvo_env.util import grid, sizes


def env_offsets(positions: NDArray[np.float64], margin: float = 0.0) -> NDArray[np.float64]:
    """Shift (E, 1, 2) that puts env e's agents beyond any neighbour search of env e - 1.

    The gap between two shifted envs is at least the largest span of an env plus ``margin``, so
    a query of radius <= ``margin`` (or a k-nearest query, k < N) never reaches another env.
    """
    E = positions.shape[0]
    span = float(np.ptp(positions, axis=1).max()) if positions.size else 0.0
    step = 2.0 * span + margin + 1.0
    shift = np.zeros((E, 1, 2))
    shift[:, 0, 0] = step * np.arange(E)
    return shift


@njit(cache=True)
def kernel_for(E, n):
    """The kernel ``_knn_dense`` runs on E envs of n agents: 0 insertion, 1 ranking, 2 env
    lanes."""
    if E * n <= sizes.KNN_INSERTION_MAX_AGENTS:
        return 0
    if E >= sizes.KNN_LANES_MIN_ENVS:
        return 2
    if sizes.KNN_RANKED_MIN_AGENTS <= n <= sizes.KNN_RANKED_MAX_AGENTS:
        return 1
    return 0


@njit(cache=True)
def _knn_dense(x, k, dist, idx):
    """k nearest of each agent in its env, nearest first; a tie goes to the lower index (the
    order of a stable sort on the squared distance). All three kernels give it bit for bit."""
    kernel = kernel_for(x.shape[0], x.shape[1])
    if kernel == 2:
        _knn_lanes(x, k, dist, idx)
    elif kernel == 1:
        _knn_ranked(x, k, dist, idx)
    else:
        _knn_inserted(x, k, dist, idx)


@njit(cache=True)
def _knn_inserted(x, k, dist, idx):
    """``_knn_dense`` by insertion into a sorted list: a strictly smaller squared distance
    goes first, so ties keep the lower index."""
    E, n = x.shape[0], x.shape[1]
    d2 = np.empty(k)
    for e in range(E):
        for i in range(n):
            m = 0
            for j in range(n):
                if j == i:
                    continue
                dx = x[e, i, 0] - x[e, j, 0]
                dy = x[e, i, 1] - x[e, j, 1]
                v = dx * dx + dy * dy
                if m == k and v >= d2[k - 1]:
                    continue
                p = m if m < k else k - 1
                while p > 0 and d2[p - 1] > v:
                    if p < k:
                        d2[p] = d2[p - 1]
                        idx[e, i, p] = idx[e, i, p - 1]
                    p -= 1
                d2[p] = v
                idx[e, i, p] = j
                if m < k:
                    m += 1
            for p in range(k):
                dist[e, i, p] = np.sqrt(d2[p])


@njit(cache=True)
def _knn_ranked(x, k, dist, idx):
    """``_knn_dense`` by ranks: agent j's rank among agent i's neighbours counts the
    neighbours q nearer than j, and those as near with q < j. ``d2`` is symmetric, so for one
    (j, q) the count runs over all agents i along a row, branch-free and vectorised."""
    E, n = x.shape[0], x.shape[1]
    d2 = np.empty((n, n))
    rank = np.empty(n, dtype=np.int64)
    # slot k takes every neighbour ranked k or beyond, so the scatter needs no branch
    near_d2 = np.empty((n, k + 1))
    near = np.empty((n, k + 1), dtype=np.int64)
    for e in range(E):
        for j in range(n):
            for i in range(n):
                dx = x[e, i, 0] - x[e, j, 0]
                dy = x[e, i, 1] - x[e, j, 1]
                d2[j, i] = dx * dx + dy * dy
            d2[j, j] = np.inf
        for j in range(n):
            rank[:] = 0
            for q in range(j):
                for i in range(n):
                    rank[i] += d2[q, i] <= d2[j, i]
            for q in range(j + 1, n):
                for i in range(n):
                    rank[i] += d2[q, i] < d2[j, i]
            for i in range(n):
                s = min(rank[i], k)
                near_d2[i, s] = d2[j, i]
                near[i, s] = j
        for i in range(n):
            for p in range(k):
                dist[e, i, p] = np.sqrt(near_d2[i, p])
                idx[e, i, p] = near[i, p]


@njit(cache=True)
def _slot_update(d2_before, d2_slot, near_before, near_slot, d2, j):
    """One slot of a sorted list, in every env at once, as ``_knn_inserted`` would leave it
    after offering neighbour j at squared distance ``d2``: the slot takes the one before it if
    that is farther than ``d2``, else ``d2`` if the slot itself is farther, else stays. Loads
    come before the selects so that the loop vectorises."""
    for e in range(d2.shape[0]):
        before, slot, v = d2_before[e], d2_slot[e], d2[e]
        i_before, i_slot = near_before[e], near_slot[e]
        shift, take = before > v, slot > v
        kept = v if take else slot
        i_kept = j if take else i_slot
        d2_slot[e] = before if shift else kept
        near_slot[e] = i_before if shift else i_kept


@njit(cache=True)
def _knn_lanes(x, k, dist, idx):
    """``_knn_dense`` across envs: agent i's sorted list of every env is a column of
    (k + 1, E) arrays whose row 0 is a sentinel nearer than anything, and each neighbour j is
    offered to all envs at once, slot by slot from the last (``_slot_update``)."""
    E, n = x.shape[0], x.shape[1]
    xs = np.empty((n, E))
    ys = np.empty((n, E))
    for e in range(E):
        for i in range(n):
            xs[i, e] = x[e, i, 0]
            ys[i, e] = x[e, i, 1]
    d2_list = np.empty((k + 1, E))
    near = np.empty((k + 1, E), dtype=np.int64)
    d2 = np.empty(E)
    for i in range(n):
        d2_list[0] = -1.0
        d2_list[1:] = np.inf
        near[:] = 0
        for j in range(n):
            if j == i:
                continue
            for e in range(E):
                dx = xs[i, e] - xs[j, e]
                dy = ys[i, e] - ys[j, e]
                d2[e] = dx * dx + dy * dy
            for p in range(k, 0, -1):
                _slot_update(d2_list[p - 1], d2_list[p], near[p - 1], near[p], d2, j)
        for e in range(E):
            for p in range(k):
                dist[e, i, p] = np.sqrt(d2_list[p + 1, e])
                idx[e, i, p] = near[p + 1, e]


@njit(cache=True)
def knn_dense_arrays(x, k):
    """``_knn_dense`` with its outputs allocated here."""
    dist = np.empty((x.shape[0], x.shape[1], k))
    idx = np.empty((x.shape[0], x.shape[1], k), dtype=np.int64)
    _knn_dense(x, k, dist, idx)
    return dist, idx


def nearest_neighbors(
    positions: NDArray[np.float64], k: int
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Distances and indices (..., N, k) of each agent's k nearest other agents in its own env,
    nearest first; indices are local to the env.

    Ties are broken by the lower index on the dense path, so results are reproducible.
    """
    n = positions.shape[-2]
    lead = positions.shape[:-2]
    k = min(k, n - 1)
    if k <= 0:
        return np.zeros((*lead, n, 0)), np.zeros((*lead, n, 0), dtype=np.int64)
    flat = np.asarray(positions, dtype=np.float64)
    if flat.ndim != 3:
        flat = flat.reshape(-1, n, 2)
    if n <= sizes.ALL_PAIRS_MAX_AGENTS:
        dist, idx = knn_dense_arrays(flat, k)
        if len(lead) == 1:
            return dist, idx
        return dist.reshape(*lead, n, k), idx.reshape(*lead, n, k)
    E = flat.shape[0]
    shifted = (flat + env_offsets(flat)).reshape(-1, 2)
    _, idx = cKDTree(shifted).query(shifted, k=k + 1)
    own = idx == np.arange(E * n)[:, None]
    keep = ~own
    # a coincident neighbour may come before the agent itself; then drop the last one instead
    keep[own.sum(axis=1) == 0, -1] = False
    idx = idx[keep].reshape(E, n, k) - (n * np.arange(E))[:, None, None]
    rel = np.take_along_axis(flat[:, None, :, :], idx[..., None], axis=2) - flat[:, :, None, :]
    d = np.sqrt(np.einsum("...j,...j->...", rel, rel))
    return d.reshape(*lead, n, k), idx.reshape(*lead, n, k).astype(np.int64)


def nearest_distance(positions: NDArray[np.float64]) -> NDArray[np.float64]:
    """Distance (..., N) from each agent to its nearest neighbour (inf for a lone agent)."""
    n = positions.shape[-2]
    if n < 2:
        return np.full(positions.shape[:-1], np.inf)
    return grid.nearest_distance(positions.reshape(-1, n, 2)).reshape(positions.shape[:-1])
