"""Which pairs of agents the filter examines: all pairs of an env, those within a radius, or
those within each agent's own radius (exact culling: every pair whose row can bind is kept).

Pairs are flat agent indices ``e * N + i`` with I < J, in a fixed order, and never cross envs.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env.responsibility.svo import (
    Weighting,
    pair_omega,
    share_of,
    symmetric_envs,
    weight_matrix,
)
from rsvo_env.util import grid, sizes

# (floor (E, N, K), group (E, N), required pairs (P, 2)): see weight_floor and theta_floor
Floor = tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]]

# Groups of scores the large-N pair search keeps apart (theta_floor): at most this many, each
# spanning a factor GROUP_RATIO (or its square, its fourth power, ... when more are occupied).
# Since the search keeps only pairs that can bind in their disks (projection_disk), wider
# groups cost fewer queries than their looser floors add (1.5 against 1.25: about 10 % less
# per step at N = 1,000 to 30,000 with theta 1..10, measured alternating in one process).
THETA_GROUPS = 16
GROUP_RATIO = 1.5


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
    :func:`sensing_radius` of its own smallest positive weight (0 for an agent without one).
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
    """:func:`agent_radii` in one compiled pass: the root of ``w gamma d^2 - 2 u d - w gamma
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


def weight_floor(omega: NDArray) -> Floor:
    """For weight matrices (E, N, N): each agent's smallest positive weight (E, N, 1) (inf when
    it has none), one group of all agents (E, N), and the pairs (P, 2), flat indices
    ``e * N + i`` with i < j, in which either side has weight 0: such a row binds at any
    distance, so no radius may drop it."""
    E, n = omega.shape[:2]
    off = ~np.eye(n, dtype=bool)
    floor = np.where(off & (omega > 0), omega, np.inf).min(axis=-1)
    zero = off & ((omega == 0) | (np.swapaxes(omega, -1, -2) == 0)) & np.triu(off)
    e, i, j = np.nonzero(zero)
    required = np.stack([e * n + i, e * n + j], axis=1).astype(np.int64)
    return floor[..., None], np.zeros((E, n), dtype=np.int64), required


# What the floors give away to rounding, absolute: every weight the filter uses is
# ``pair_omega`` of two scores, or 1 minus that, each within WEIGHT_ROUNDING of the exact weight
# (``docs/math.md``: the share's division, pi times it, the cosine's own error, the final sum,
# with room to spare), so a floor lowered by twice that, plus the subtraction's rounding, lies
# below every weight it stands for, at any ratio of scores.
WEIGHT_ROUNDING = 32.0 * np.finfo(float).eps
FLOOR_MARGIN = 2.0 * WEIGHT_ROUNDING + np.finfo(float).eps


def score_groups(theta: NDArray) -> tuple[NDArray[np.int64], int]:
    """Geometric bins of the scores (E, N): bin k holds ``GROUP_RATIO**k <= theta <
    GROUP_RATIO**(k + 1)``, the occupied bins numbered from 0 in order, a theta = 0 agent in the
    lowest; where more than ``THETA_GROUPS`` bins are occupied, the bins widen (the ratio
    squared, and again) until at most that many are. Returns (group (E, N), K)."""
    pos = theta > 0
    if not pos.any():
        return np.zeros(theta.shape, dtype=np.int64), 1
    log = np.log(np.where(pos, theta, 1.0)) / np.log(GROUP_RATIO)
    width = 1.0
    while True:
        raw = np.floor(log / width).astype(np.int64)
        occupied = np.unique(raw[pos])
        if len(occupied) <= THETA_GROUPS:
            break
        width *= 2.0
    group = np.searchsorted(occupied, raw)
    return np.where(pos, group, 0).astype(np.int64), len(occupied)


def theta_floor(theta: NDArray, mode: str) -> Floor:
    """:func:`weight_floor` of a named weighting from the scores (E, N) alone, in O(N) time and
    memory at any ratio of scores, and finer: the agents fall into up to ``THETA_GROUPS``
    groups (:func:`score_groups`), and agent i gets its smallest positive weight against each
    group (E, N, K). The weight of i against j grows with theta_j, so that is the weight against
    the group's smallest positive score, lowered by ``FLOOR_MARGIN`` (a bound on the rounding of
    the weights the filter uses, not a guess); a floor the margin takes to 0 or below searches
    the whole group (an infinite radius). A zero weight arises exactly between a theta = 0 agent
    and a positive one: those pairs are listed."""
    E, n = theta.shape
    none = np.zeros((0, 2), dtype=np.int64)
    if mode == "symmetric" or n < 2:
        floor = np.full((E, n, 1), 0.5 if n > 1 else np.inf)  # exactly 0.5: no rounding
        return floor, np.zeros((E, n), dtype=np.int64), none
    group, K = score_groups(theta)
    pos = np.where(theta > 0, theta, np.inf)
    member = group[..., None] == np.arange(K)  # (E, N, K)
    low_pos = np.where(member, pos[..., None], np.inf).min(axis=1)  # (E, K)
    low = np.where(member, theta[..., None], np.inf).min(axis=1)
    ti = theta[..., None]
    vs_pos = pair_omega(ti, np.where(np.isfinite(low_pos), low_pos, 1.0)[:, None, :])
    w = np.where(
        ti > 0,
        np.where(np.isfinite(low_pos)[:, None, :], vs_pos, np.inf),
        np.where(np.isfinite(low)[:, None, :], pair_omega(ti, low[:, None, :]), np.inf),
    )
    floor = w - FLOOR_MARGIN  # inf stays inf: no member to search
    e, i = np.nonzero(theta == 0)
    if len(e) == 0:
        return floor, group, none
    # every (theta = 0, theta > 0) pair of an env
    e2, j = np.nonzero(theta[e] > 0)
    a, b = e[e2] * n + i[e2], e[e2] * n + j
    return floor, group, np.stack([np.minimum(a, b), np.maximum(a, b)], axis=1).astype(np.int64)


def floor_of(theta: NDArray, mode: Weighting, matrix: NDArray | None = None) -> Floor:
    """The floor of weighting ``mode`` for scores (E, N): :func:`theta_floor` for a named mode
    where it applies, else :func:`weight_floor` of the weight matrices (``matrix``, or built)."""
    if isinstance(mode, str):
        return theta_floor(theta, mode)
    return weight_floor(weight_matrix(theta, mode) if matrix is None else matrix)


def pairs_within_agent_radii(
    positions: NDArray, radius: NDArray, floor: Floor, disk: tuple | None = None
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Pairs (I < J, flat indices) of agents of the same env closer than the larger of their
    radii against each other's group (``radius`` (E, N, K) from ``floor``), plus the floor's
    required pairs, sorted: the all-pairs order, kept. ``disk``: see
    :func:`grid.pairs_within_radii`."""
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
    those within ``radius`` (the compiled grid of :mod:`rsvo_env.util.grid`, env by env, for
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


@njit(cache=True)
def _shares(theta, I, J):
    """:func:`responsibility.share_of` of flat pairs."""
    P = I.shape[0]
    out = np.empty(P)
    for p in range(P):
        out[p] = share_of(theta[I[p]], theta[J[p]])
    return out


@njit(cache=True)
def _both_sides(cos_pi_share, symmetric, I, n):
    """(P, 2): ``omega = (1 + cos(pi share)) / 2`` of each pair and ``1 - omega``; 1/2 in the
    envs marked ``symmetric`` (E,)."""
    P = I.shape[0]
    out = np.empty((P, 2))
    mixed = symmetric.any()  # else no pair needs its env (an integer division a pair)
    for p in range(P):
        w = 0.5 * (1.0 + cos_pi_share[p])
        if mixed and symmetric[I[p] // n]:
            w = 0.5
        out[p, 0] = w
        out[p, 1] = 1.0 - w
    return out


def scored_pairs(
    theta: NDArray, I: NDArray, J: NDArray, symmetric: NDArray[np.bool_] | None = None
) -> NDArray[np.float64]:
    """(P, 2) omega_IJ, omega_JI of flat pairs from validated scores (E, N) (Thm. 1: the
    weight matrix's entries, ``pair_omega`` above the diagonal), the same numbers as
    :func:`responsibility.scored_weight` in two compiled passes and numpy's cosine;
    ``symmetric`` (E,): envs whose weighting is symmetric (1/2 each)."""
    E, n = theta.shape
    if symmetric is None:
        symmetric = np.zeros(E, dtype=bool)
    share = _shares(np.ascontiguousarray(theta, dtype=np.float64).reshape(-1), I, J)
    share *= np.pi
    return _both_sides(np.cos(share, out=share), symmetric, I, n)


def weights_of(
    theta: NDArray, modes: Sequence[Weighting], I: NDArray, J: NDArray
) -> NDArray[np.float64]:
    """(P, 2) omega_IJ, omega_JI of flat pairs from the scores (E, N) and each env's weighting:
    from the scores where every one is named, else through each env's matrix."""
    E, n = theta.shape
    if any(callable(m) for m in modes):
        W = np.stack([weight_matrix(t, m) for t, m in zip(theta, modes, strict=True)])
        return omega_pairs(W.reshape(E * n, n), I, J, n)
    return scored_pairs(theta, I, J, symmetric_envs(modes))
