"""Responsibility-associated Social Value Orientation (R-SVO) and the responsibility weights.

Paper: Def. 1 (eq. ``rsvo``) gives ``phi_i = theta_i / (theta_i + theta_j) * pi/2``; Thm. 1 gives
the Local Pairwise Responsibility Weight ``omega_i = cos^2(phi_i)``. Since
``phi_i + phi_j = pi/2``, ``omega_i + omega_j = 1``, which is what makes the decentralized rows sum
to the centralized CBF condition (eq. ``centralized-cbf``).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from rsvo_env.util.validation import check_theta, shown

WEIGHTING_MODES = ("asymmetric", "symmetric")
Weighting = str | Callable[[NDArray[np.float64]], ArrayLike]


def _pair(theta_i: ArrayLike, theta_j: ArrayLike) -> tuple[NDArray, NDArray]:
    ti = check_theta(theta_i, name="theta_i", allow_scalar=True)
    tj = check_theta(theta_j, name="theta_j", allow_scalar=True)
    wide_i, wide_j = np.broadcast_arrays(ti, tj)
    return wide_i, wide_j


def r_svo(theta_i: ArrayLike, theta_j: ArrayLike) -> NDArray[np.float64] | float:
    """R-SVO angle ``phi_i = theta_i/(theta_i+theta_j) * pi/2`` (paper, Def. 1, eq. ``rsvo``).

    ``theta_i = theta_j = 0`` has no value in the paper; we define ``phi = pi/4`` there (equal
    personalities), so that ``omega = 0.5``.

    Args:
        theta_i: Agent i's personality score(s), >= 0 (small: egoistic); a number or an array.
        theta_j: The other agent's score(s), broadcast against ``theta_i``.

    Returns:
        The angle ``phi_i`` in [0, pi/2]: a float for two numbers, else an array of their
        broadcast shape.

    Raises:
        ValueError: A score is negative, NaN, infinite or not a real number (naming its index).
    """
    ti, tj = _pair(theta_i, theta_j)
    phi = _share(ti, tj) * (np.pi / 2)
    return float(phi) if phi.ndim == 0 else phi


def _share(ti: NDArray, tj: NDArray) -> NDArray:
    """``theta_i / (theta_i + theta_j)``, 0.5 where both are 0; inputs already validated.

    Where the sum overflows (``1e308 + 1e308`` is inf, which made such a pair's weights sum
    to 2) both scores are halved first: the same share, to rounding. Equal scores give exactly
    1/2 at any magnitude."""
    with np.errstate(over="ignore"):  # an overflow is the case handled next, not an error
        total = ti + tj
    if not np.isfinite(total).all():
        ti, tj = np.broadcast_arrays(ti, tj)
        big = ~np.isfinite(total)
        ti, tj = np.where(big, 0.5 * ti, ti), np.where(big, 0.5 * tj, tj)
        total = ti + tj
    safe = np.where(total > 0, total, 1.0)
    return np.where(total > 0, ti / safe, 0.5)


def pair_omega(ti: NDArray, tj: NDArray) -> NDArray:
    """omega of validated scores, vectorised: ``(1 + cos(pi * share)) / 2`` (Def. 1, Thm. 1)."""
    return 0.5 * (1.0 + np.cos(np.pi * _share(ti, tj)))


def scored_weight(ti: NDArray, tj: NDArray, symmetric: NDArray | bool) -> NDArray:
    """omega of agent i against agent j, i < j, from the scores: the weight matrix's upper
    triangle (Thm. 1; its lower triangle is ``1 -`` this), 0.5 where ``symmetric``."""
    return np.where(symmetric, 0.5, pair_omega(ti, tj))


def symmetric_envs(modes: Sequence[Weighting]) -> NDArray[np.bool_]:
    """(E,): which envs' named weighting is ``symmetric``."""
    return np.array([m == "symmetric" for m in modes])


def responsibility_weight(theta_i: ArrayLike, theta_j: ArrayLike) -> NDArray[np.float64] | float:
    """Local Pairwise Responsibility Weight ``omega_i = cos^2(phi_i)`` (paper, Thm. 1).

    Evaluated as ``(1 + cos(2 phi)) / 2``, which is exactly 0.5 at ``phi = pi/4``, 0 at
    ``pi/2`` and 1 at 0 (``cos(phi)**2`` is 0.5000000000000001 at ``pi/4``); 0.5 when both
    scores are 0. A smaller theta (egoist) gives a larger omega, a looser row
    ``A_i u <= omega_i b_i``; ``omega_i + omega_j = 1``.

    Args:
        theta_i: Agent i's personality score(s), >= 0; a number or an array.
        theta_j: The other agent's score(s), broadcast against ``theta_i``.

    Returns:
        ``omega_i`` in [0, 1]: a float for two numbers, else an array of the broadcast shape.

    Raises:
        ValueError: A score is negative, NaN, infinite or not a real number (naming its index).
    """
    omega = pair_omega(*_pair(theta_i, theta_j))
    return float(omega) if omega.ndim == 0 else omega


def weight_matrix(theta: ArrayLike, mode: Weighting = "asymmetric") -> NDArray[np.float64]:
    """The (N, N) matrix ``W[i, j] = omega_i`` of agent i against agent j (Thm. 1).

    The diagonal is 0 (no row). The upper triangle is computed and the lower one set to
    ``1 - W.T``, so the pair sum is 1 to one rounding.

    Args:
        theta: The scores (N,), >= 0, or a batch of them (E, N), which gives (E, N, N).
        mode: ``"asymmetric"``, the paper's R-SVO weights; ``"symmetric"``, 0.5 everywhere (the
            homogeneous baseline of the paper's symmetric examples); or a callable
            ``theta -> W``, validated: entries in [0, 1] and ``W + W.T == 1`` off the diagonal
            (to 1e-9), since without that the pair rows no longer sum to the centralized
            condition.

    Returns:
        The weight matrix (N, N), or (E, N, N) for a batch.

    Raises:
        ValueError: A bad score (naming its index), an unknown mode, or a callable's matrix of
            the wrong shape or outside the conditions above.
    """
    raw = np.asarray(theta)
    if raw.ndim == 2:
        return (
            np.stack([weight_matrix(t, mode) for t in raw])
            if callable(mode)
            else (named_weights(np.stack([check_theta(t) for t in raw]), mode))
        )
    th = check_theta(theta, name="theta")
    if callable(mode):
        w = np.array(mode(th.copy()), dtype=np.float64)
        return validate_weight_matrix(w, th.shape[0])
    return named_weights(th, mode)


# Rows of a weight matrix computed at once: bounds the temporaries to about 32 MB.
BLOCK_ENTRIES = 1 << 22


def check_weighting(mode: Weighting, theta: ArrayLike) -> None:
    """Refuse an unknown mode, or a callable whose matrix for ``theta`` (N,) is not a valid
    weight matrix, without building a matrix for a named mode."""
    if callable(mode):
        weight_matrix(theta, mode)
    elif not isinstance(mode, str) or mode not in WEIGHTING_MODES:
        raise _unknown(mode)


def _unknown(mode: object) -> ValueError:
    return ValueError(
        f"weighting mode {shown(mode)} is unknown; use one of {WEIGHTING_MODES} or a callable"
    )


@njit(cache=True, inline="always")
def share_of(ti: float, tj: float) -> float:
    """One pair's ``theta_i / (theta_i + theta_j)``, compiled, as ``_share`` computes it
    (both halved where the sum overflows; 0.5 where both are 0)."""
    total = ti + tj
    if not np.isfinite(total):
        ti, tj = 0.5 * ti, 0.5 * tj
        total = ti + tj
    return ti / total if total > 0.0 else 0.5


@njit(cache=True)
def _upper_shares(th):
    """(K, N, N): ``share_of`` above the diagonal of each of K envs' scores (K, N); 0
    elsewhere."""
    K, n = th.shape
    out = np.zeros((K, n, n))
    for e in range(K):
        for i in range(n):
            for j in range(i + 1, n):
                out[e, i, j] = share_of(th[e, i], th[e, j])
    return out


@njit(cache=True)
def _from_upper_cosines(c):
    """Weight matrices (K, N, N) from ``cos(pi share)`` above the diagonal: ``(1 + c) / 2``
    there, ``1 -`` its transpose below, 0 on the diagonal; and each matrix's smallest
    off-diagonal weight (K,)."""
    K, n = c.shape[0], c.shape[1]
    w = np.empty((K, n, n))
    smallest = np.full(K, np.inf)
    for e in range(K):
        for i in range(n):
            w[e, i, i] = 0.0
            for j in range(i + 1, n):
                up = 0.5 * (1.0 + c[e, i, j])
                w[e, i, j] = up
                w[e, j, i] = 1.0 - up
                smallest[e] = min(smallest[e], up, 1.0 - up)
    return w, smallest


def _one_block(th: NDArray[np.float64]) -> bool:
    """Whether the asymmetric matrices of scores (..., N) are built at once (compiled)."""
    n = th.shape[-1]
    return n >= 2 and th.size * n <= BLOCK_ENTRIES


def _compiled_weights(th: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
    """Asymmetric matrices (..., N, N) and their smallest weights (...,) of scores (..., N) in
    two compiled passes and numpy's cosine (a reset pays for calls, not for arithmetic)."""
    n = th.shape[-1]
    share = _upper_shares(np.ascontiguousarray(th, dtype=np.float64).reshape(-1, n))
    share *= np.pi
    w, smallest = _from_upper_cosines(np.cos(share, out=share))
    return w.reshape(*th.shape, n), smallest.reshape(th.shape[:-1])


def named_weights_and_floor(
    th: NDArray[np.float64], mode: str
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``named_weights`` of scores (..., N), and each matrix's smallest off-diagonal
    weight (``smallest_weight``), the one block's from the same compiled pass."""
    if mode == "asymmetric" and _one_block(th):
        return _compiled_weights(th)
    w = named_weights(th, mode)
    return w, np.asarray(smallest_weight(w), dtype=np.float64).reshape(th.shape[:-1])


def named_weights(th: NDArray[np.float64], mode: str) -> NDArray[np.float64]:
    """The matrices of a named mode (``weight_matrix``) for scores (..., N) that are
    already valid (a caller that checked them, as the core does at every reset), a block of
    rows at a time so a crowd of 10,000 needs the matrix and no N x N temporaries."""
    n = th.shape[-1]
    if mode == "symmetric":
        w = np.full((*th.shape, n), 0.5)
    elif mode == "asymmetric" and _one_block(th):
        return _compiled_weights(th)[0]
    elif mode == "asymmetric":
        w = np.empty((*th.shape, n))
        step = max(1, BLOCK_ENTRIES // max(n, 1))
        for a in range(0, n, step):
            w[..., a : a + step, :] = pair_omega(th[..., a : a + step, None], th[..., None, :])
        # the lower triangle is 1 - W.T, so each pair's weights sum to 1 to one rounding
        for a in range(0, n, step):
            b = min(a + step, n)
            w[..., a:b, :a] = 1.0 - np.swapaxes(w[..., :a, a:b], -1, -2)
            block = w[..., a:b, a:b]
            low = ~_upper(b - a)
            block[..., low] = 1.0 - np.swapaxes(block, -1, -2)[..., low]
    else:
        raise _unknown(mode)
    diag = np.arange(n)
    w[..., diag, diag] = 0.0
    return w


@functools.lru_cache(maxsize=64)
def _upper(n: int) -> NDArray[np.bool_]:
    """(n, n): True on and above the diagonal (the entries a weight matrix computes)."""
    mask = np.triu(np.ones((n, n), dtype=bool))
    mask.flags.writeable = False
    return mask


def validate_weight_matrix(w: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    """Check a user-given weight matrix: shape (n, n), finite, in [0, 1], ``W + W.T = 1``."""
    if w.shape != (n, n):
        raise ValueError(f"weight matrix has shape {w.shape}, expected ({n}, {n})")
    off = ~np.eye(n, dtype=bool)
    bad = off & ~(np.isfinite(w) & (w >= 0.0) & (w <= 1.0))
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise ValueError(
            f"weight matrix entry omega[{i}, {j}] = {shown(float(w[i, j]))} is not in [0, 1]"
        )
    pair_sum = w + w.T
    bad = off & (np.abs(pair_sum - 1.0) > 1e-9)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise ValueError(
            f"weight matrix breaks omega[{i}, {j}] + omega[{j}, {i}] = 1: "
            f"{shown(float(w[i, j]))} + {shown(float(w[j, i]))} = {shown(float(pair_sum[i, j]))}"
        )
    w = w.copy()
    np.fill_diagonal(w, 0.0)
    return w


def theta_for_weight(omega: float) -> tuple[float, float]:
    """Scores (theta_i, theta_j), summing to 1, that give agent i the weight ``omega``.

    Inverts Thm. 1: ``omega = cos^2(pi/2 * share)`` gives ``share = acos(sqrt(omega)) / (pi/2)``.
    The paper's position swap is stated in weights (0.8/0.2, 0.5/0.5, 0.2/0.8).
    """
    if not 0.0 <= omega <= 1.0:
        raise ValueError(f"omega = {shown(omega)} must be in [0, 1]")
    share = float(np.arccos(np.sqrt(omega)) / (np.pi / 2))
    return share, 1.0 - share


def min_pair_weight(theta: NDArray[np.float64], mode: Weighting) -> float:
    """Smallest omega over all pairs, in O(N): the most altruistic agent against the most egoistic.

    Used to bound the sensing radius beyond which no row can bind (``docs/math.md``).
    """
    if len(theta) < 2:
        return 0.5
    if mode == "symmetric":
        return 0.5
    if mode == "asymmetric":
        order = np.sort(theta)
        return float(pair_omega(order[-1], order[0]))
    w = weight_matrix(theta, mode)
    return float(w[~np.eye(len(theta), dtype=bool)].min())


def smallest_weight(omega: NDArray[np.float64]) -> NDArray[np.float64] | float:
    """Smallest off-diagonal omega of each (N, N) matrix of (..., N, N); 0.5 for one agent.
    A block of rows at a time, so no copy of the matrix is made."""
    n = omega.shape[-1]
    if n < 2:
        return np.full(omega.shape[:-2], 0.5) if omega.ndim > 2 else 0.5
    if n * n <= BLOCK_ENTRIES:  # one block
        out = np.where(_upper(n) & _upper(n).T, np.inf, omega).min(axis=(-2, -1))
        return out if omega.ndim > 2 else float(out)
    out = np.full(omega.shape[:-2], np.inf)
    step = max(1, BLOCK_ENTRIES // n)
    for a in range(0, n, step):
        block = omega[..., a : a + step, :].copy()
        rows = np.arange(block.shape[-2])
        block[..., rows, a + rows] = np.inf
        out = np.minimum(out, block.min(axis=(-2, -1)))
    return out if omega.ndim > 2 else float(out)
