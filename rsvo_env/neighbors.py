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

from rsvo_env import grid

# Below this many agents all pairs are cheaper than a KD-tree.
DENSE_MAX_AGENTS = 64


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
def _knn_dense(x, k, dist, idx):
    """k nearest of each agent in its env, by insertion into a sorted list: a strictly smaller
    squared distance goes first, so ties keep the lower index (a stable sort)."""
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
def _knn_dense_new(x, k):
    """:func:`_knn_dense` with its outputs allocated here."""
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
    if n <= DENSE_MAX_AGENTS:
        dist, idx = _knn_dense_new(flat, k)
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
