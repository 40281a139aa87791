"""Nearest-neighbour queries over agent positions, batch-first: (E, N, 2) or (N, 2).

Dense for few agents, one KD-tree over all envs for many. Pairs never cross envs: in the tree each
env is shifted along x by more than any distance inside an env, and distances are recomputed from
the unshifted positions.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

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
    if n <= DENSE_MAX_AGENTS:
        diff = positions[..., :, None, :] - positions[..., None, :, :]
        d2 = np.einsum("...ijk,...ijk->...ij", diff, diff)
        diag = np.arange(n)
        d2[..., diag, diag] = np.inf
        idx = np.argsort(d2, axis=-1, kind="stable")[..., :k]
        return np.sqrt(np.take_along_axis(d2, idx, axis=-1)), idx.astype(np.int64)
    flat = positions.reshape(-1, n, 2)
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
    if positions.shape[-2] < 2:
        return np.full(positions.shape[:-1], np.inf)
    return nearest_neighbors(positions, 1)[0][..., 0]
