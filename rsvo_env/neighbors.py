"""Nearest-neighbour queries over agent positions: dense for few agents, a KD-tree for many."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

# Below this many agents all pairs are cheaper than a KD-tree.
DENSE_MAX_AGENTS = 64


def nearest_neighbors(
    positions: NDArray[np.float64], k: int
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Distances and indices (N, k) of each agent's k nearest other agents, nearest first.

    Ties are broken by the lower index, whichever path answers, so results are reproducible.
    """
    n = positions.shape[0]
    k = min(k, n - 1)
    if k <= 0:
        return np.zeros((n, 0)), np.zeros((n, 0), dtype=np.int64)
    if n <= DENSE_MAX_AGENTS:
        diff = positions[:, None, :] - positions[None, :, :]
        d2 = np.einsum("ijk,ijk->ij", diff, diff)
        np.fill_diagonal(d2, np.inf)
        idx = np.argsort(d2, axis=1, kind="stable")[:, :k]
        return np.sqrt(np.take_along_axis(d2, idx, axis=1)), idx.astype(np.int64)
    d, idx = cKDTree(positions).query(positions, k=k + 1)
    # drop each agent itself (a coincident neighbour may come first)
    own = idx == np.arange(n)[:, None]
    keep = ~own
    keep[own.sum(axis=1) == 0, -1] = False
    d = d[keep].reshape(n, k)
    idx = idx[keep].reshape(n, k)
    return d, idx.astype(np.int64)


def nearest_distance(positions: NDArray[np.float64]) -> NDArray[np.float64]:
    """Distance from each agent to its nearest neighbour (inf for a lone agent)."""
    if positions.shape[0] < 2:
        return np.full(positions.shape[0], np.inf)
    return nearest_neighbors(positions, 1)[0][:, 0]
