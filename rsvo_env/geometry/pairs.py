"""Which pairs of agents the filter examines: all pairs of an env, those within a radius, or
those within each agent's own radius (exact culling: every pair whose row can bind is kept).

Pairs are flat agent indices ``e * N + i`` with I < J, in a fixed order, and never cross envs.
"""

from __future__ import annotations

import functools

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env.responsibility.pair_weights import Floor
from rsvo_env.util import grid, sizes


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
    omega_floor: NDArray, gamma: float, speed: NDArray, reach: NDArray
) -> NDArray[np.float64]:
    """Per agent, the distance beyond which none of its rows with a positive weight can bind:
    ``sensing_radius`` of its own smallest positive weight (0 for an agent without one).
    ``omega_floor`` (E, N, K); ``speed`` (E, N): the largest norm its action can take (its
    box's largest input vector, or less: ``rsvo_env.filter.projection_disk``); ``reach`` (E, N): the
    largest safe distance of its pairs, ``r_i + max_j r_j``."""
    f = np.ascontiguousarray(omega_floor, dtype=np.float64)
    out = np.empty(f.shape)
    _agent_radii(
        f,
        float(gamma),
        np.ascontiguousarray(speed, dtype=np.float64),
        np.ascontiguousarray(reach, dtype=np.float64),
        out,
    )
    return out


@njit(cache=True)
def _agent_radii(floor, gamma, speed, reach, out):
    """``agent_radii`` in one compiled pass: the root of ``w gamma d^2 - 2 u d - w gamma
    R^2`` per floor ``w``."""
    E, n, K = floor.shape
    for e in range(E):
        for i in range(n):
            u, R = speed[e, i], reach[e, i]
            for k in range(K):
                w = floor[e, i, k]
                if not np.isfinite(w):
                    out[e, i, k] = 0.0  # no member to search
                elif w > 0.0:
                    wg = w * gamma
                    # the root is exact only in exact arithmetic: a pair right at it stays examined
                    out[e, i, k] = (u + np.sqrt(u * u + (wg * R) ** 2)) / wg * (1.0 + 1e-9)
                else:
                    # a floor at or below 0 (a weight within rounding of 0) binds at any distance
                    out[e, i, k] = np.inf


def pairs_within_agent_radii(
    positions: NDArray, radius: NDArray, floor: Floor, disk: tuple | None = None
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Pairs (I < J, flat indices) of agents of the same env closer than the larger of their
    radii against each other's group (``radius`` (E, N, K) from ``floor``), plus the floor's
    required pairs, sorted: the all-pairs order, kept. ``disk``: see
    ``grid.pairs_within_radii``."""
    I, J = grid.pairs_within_radii(positions, radius, floor[1], disk)
    required = floor[2]
    if len(required) == 0:
        return I, J
    pairs = np.unique(np.concatenate([np.stack([I, J], axis=1), required]), axis=0)
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
    those within ``radius`` (the compiled grid of ``rsvo_env.util.grid``, env by env, for
    many agents). ``positions`` is (E, N, 2)."""
    E, n = positions.shape[0], positions.shape[1]
    if n < 2:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty
    if np.isfinite(radius) and radius > 0.0 and n > sizes.ALL_PAIRS_MAX_AGENTS:
        # the compiled grid: the same pairs, sorted, without a tree's Python-level lists
        return grid.pairs_within_radii(positions, np.full((E, n), float(radius)))
    I, J = all_pairs(n, E)
    if np.isfinite(radius):
        flat = positions.reshape(-1, 2)
        keep = np.linalg.norm(flat[I] - flat[J], axis=1) <= radius
        I, J = I[keep], J[keep]
    return I, J
