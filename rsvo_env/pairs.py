"""Which pairs of agents the filter examines: all pairs of an env, those within a radius, or
those within each agent's own radius (exact culling: every pair whose row can bind is kept).

Pairs are flat agent indices ``e * N + i`` with I < J, in a fixed order, and never cross envs.
"""

from __future__ import annotations

import functools

import numpy as np
from numba import njit
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from rsvo_env.neighbors import DENSE_MAX_AGENTS, env_offsets


def sensing_radius(
    omega_min: float, gamma: float, safety_radius: float, lo: NDArray, hi: NDArray
) -> float:
    """Distance beyond which no single-integrator row can bind (``docs/math.md``).

    A row cannot bind when ``omega gamma (d^2 - R^2) >= max_box A u``; the right side is at most
    ``2 d |U|`` with ``U`` the per-component speed bound, so the root of
    ``omega gamma d^2 - 2 |U| d - omega gamma R^2`` bounds every binding pair. Infinite when
    ``omega_min = 0`` (a fully altruistic agent must never close in on a theta = 0 agent).
    """
    if omega_min <= 0.0:
        return float("inf")
    u = float(np.hypot(*np.maximum(np.abs(lo), np.abs(hi))))
    wg = omega_min * gamma
    return (u + np.sqrt(u * u + (wg * safety_radius) ** 2)) / wg


def agent_radii(
    omega_floor: NDArray, gamma: float, safety_radius: float, lo: NDArray, hi: NDArray
) -> NDArray[np.float64]:
    """Per agent, the distance beyond which none of its rows with a positive weight can bind:
    :func:`sensing_radius` of its own smallest positive weight (0 for an agent without one)."""
    u = float(np.hypot(*np.maximum(np.abs(lo), np.abs(hi))))
    wg = np.where(np.isfinite(omega_floor), omega_floor, 0.0) * gamma
    with np.errstate(divide="ignore", invalid="ignore"):
        r = (u + np.sqrt(u * u + (wg * safety_radius) ** 2)) / wg
    return np.where(wg > 0, r, 0.0)


def weight_floor(omega: NDArray) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """For weight matrices (E, N, N): each agent's smallest positive weight (E, N) (inf when it
    has none), and the pairs (P, 2), flat indices ``e * N + i`` with i < j, in which either side
    has weight 0: such a row binds at any distance, so no radius may drop it."""
    E, n = omega.shape[:2]
    off = ~np.eye(n, dtype=bool)
    floor = np.where(off & (omega > 0), omega, np.inf).min(axis=-1)
    zero = off & ((omega == 0) | (np.swapaxes(omega, -1, -2) == 0)) & np.triu(off)
    e, i, j = np.nonzero(zero)
    return floor, np.stack([e * n + i, e * n + j], axis=1).astype(np.int64)


def pairs_within_agent_radii(
    positions: NDArray, radius: NDArray, required: NDArray | None = None
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Pairs (I < J, flat indices) of agents of the same env closer than the larger of their
    two radii (E, N), plus the ``required`` pairs (P, 2), sorted: the all-pairs order, kept."""
    E, n = positions.shape[:2]
    r = radius.reshape(-1)
    shifted = (positions + env_offsets(positions, float(r.max(initial=0.0)))).reshape(-1, 2)
    hits = cKDTree(shifted).query_ball_point(shifted, r=r, return_sorted=False)
    counts = np.fromiter((len(h) for h in hits), dtype=np.int64, count=len(hits))
    src = np.repeat(np.arange(E * n, dtype=np.int64), counts)
    dst = np.fromiter((k for h in hits for k in h), dtype=np.int64, count=int(counts.sum()))
    pairs = np.stack([np.minimum(src, dst), np.maximum(src, dst)], axis=1)[src != dst]
    if required is not None and len(required):
        pairs = np.concatenate([pairs, required])
    if len(pairs) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty
    pairs = np.unique(pairs, axis=0)  # sorted by (I, J)
    return pairs[:, 0], pairs[:, 1]


@functools.lru_cache(maxsize=64)
def all_pairs(n: int, num_envs: int = 1) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Every unordered pair (I < J) of n agents in each of ``num_envs`` envs, as flat agent
    indices ``e * n + i``, env by env in a fixed order (read-only arrays, cached)."""
    I, J = np.triu_indices(n, 1)
    base = (n * np.arange(num_envs, dtype=np.int64))[:, None]
    I, J = (base + I).ravel(), (base + J).ravel()
    I.flags.writeable = False
    J.flags.writeable = False
    return I, J


def candidate_pairs(
    positions: NDArray, radius: float = float("inf")
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Pairs (I < J, flat indices) of agents of the same env that may interact: all pairs, or
    those within ``radius``. ``positions`` is (E, N, 2); one KD-tree serves every env."""
    E, n = positions.shape[0], positions.shape[1]
    if n < 2:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty
    flat = positions.reshape(-1, 2)
    if not np.isfinite(radius) or n <= DENSE_MAX_AGENTS:
        I, J = all_pairs(n, E)
        if np.isfinite(radius):
            d = np.linalg.norm(flat[I] - flat[J], axis=1)
            keep = d <= radius
            I, J = I[keep], J[keep]
        return I, J
    shifted = (positions + env_offsets(positions, radius)).reshape(-1, 2)
    pairs = cKDTree(shifted).query_pairs(radius, output_type="ndarray")
    if len(pairs) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty
    pairs = np.sort(pairs, axis=1)
    # A fixed pair order keeps results bit-identical whatever order the tree returns.
    order = np.lexsort((pairs[:, 1], pairs[:, 0]))
    pairs = pairs[order]
    return pairs[:, 0].astype(np.int64), pairs[:, 1].astype(np.int64)


@njit(cache=True)
def omega_pairs(omega, I, J, n):
    """(P, 2) weights ``omega[e, i, j]``, ``omega[e, j, i]`` of flat pairs (I, J), from the
    weight matrices flattened to (E * n, n)."""
    P = I.shape[0]
    w = np.empty((P, 2))
    for p in range(P):
        w[p, 0] = omega[I[p], J[p] % n]
        w[p, 1] = omega[J[p], I[p] % n]
    return w
