"""The responsibility weights of pairs (paper, Thm. 1), as the filter and the controllers read
them: each pair's ``omega_ij``, ``omega_ji`` from the scores or the weight matrices, each env's
weight matrices, and each agent's weight floor (the smallest weight its rows can have, by groups
of scores), from which the pair search takes its radii (``docs/math.md``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env.responsibility.svo import (
    Weighting,
    named_weights,
    pair_omega,
    share_of,
    symmetric_envs,
    weight_matrix,
)

# (floor (E, N, K), group (E, N), required pairs (P, 2)): see weight_floor and theta_floor
Floor = tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]]

# Groups of scores the large-N pair search keeps apart (theta_floor): at most this many, each
# spanning a factor GROUP_RATIO (or its square, its fourth power, ... when more are occupied);
# wider groups cost fewer queries than their looser floors add (benchmarks/results/scaling.md)
THETA_GROUPS = 16
GROUP_RATIO = 1.5


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
    """``weight_floor`` of a named weighting from the scores (E, N) alone, in O(N) time and
    memory at any ratio of scores, and finer: the agents fall into up to ``THETA_GROUPS``
    groups (``score_groups``), and agent i gets its smallest positive weight against each
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
    """The floor of weighting ``mode`` for scores (E, N): ``theta_floor`` for a named mode
    where it applies, else ``weight_floor`` of the weight matrices (``matrix``, or built)."""
    if isinstance(mode, str):
        return theta_floor(theta, mode)
    return weight_floor(weight_matrix(theta, mode) if matrix is None else matrix)


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
    """``responsibility.share_of`` of flat pairs."""
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
    ``responsibility.scored_weight`` in two compiled passes and numpy's cosine;
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
        return omega_pairs(weight_matrices(theta, modes).reshape(E * n, n), I, J, n)
    return scored_pairs(theta, I, J, symmetric_envs(modes))


def weight_matrices(theta: NDArray, modes: Sequence[Weighting]) -> NDArray[np.float64]:
    """(E, N, N) each env's weight matrix from its scores ``theta`` (E, N) and weighting
    ``modes`` (E,), the numbers ``weights_of`` gives its pairs."""
    if any(callable(m) for m in modes):
        return np.stack([weight_matrix(t, m) for t, m in zip(theta, modes, strict=True)])
    W = named_weights(np.ascontiguousarray(theta, dtype=np.float64), "asymmetric")
    W[symmetric_envs(modes)] = 0.5
    return W
