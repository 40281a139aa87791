"""What an input box allows: its support along a row, its guaranteed deceleration, its longest
input, its support cut by a half-plane (``docs/double_integrator.md``)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def support_within(
    d: NDArray, lo: NDArray, hi: NDArray, g: NDArray, s: NDArray
) -> NDArray[np.float64]:
    """``max d . a`` over the box ``lo <= a <= hi`` ((2,), or one per row (k, 2)) cut by the
    half-plane ``g . a <= s`` (rows (k, 2)), taken at the polygon's vertices: the box corners
    inside the half-plane and the half-plane's line crossing the box edges. The caller ensures
    the polygon is not empty.
    """
    lo, hi = np.broadcast_to(lo, d.shape), np.broadcast_to(hi, d.shape)
    cand = [np.stack([a[:, 0], b[:, 1]], -1) for a in (lo, hi) for b in (lo, hi)]
    with np.errstate(divide="ignore", invalid="ignore"):
        for axis in (0, 1):
            other = 1 - axis
            for edge in (lo[:, axis], hi[:, axis]):
                t = (s - g[:, axis] * edge) / g[:, other]
                point = np.empty_like(d)
                point[:, axis], point[:, other] = edge, t
                cand.append(point)
    best = np.full(len(d), -np.inf)
    # the edge points are on the line to rounding: a relative hair of slack keeps them
    scale = np.maximum(np.abs(lo), np.abs(hi)).max(axis=1)
    tol = 1e-12 * (np.abs(g).sum(axis=1) * scale + np.abs(s))
    for c in cand:
        inside = (np.einsum("kd,kd->k", g, c) <= s + tol) & (c >= lo).all(axis=1)
        inside &= (c <= hi).all(axis=1) & np.isfinite(c).all(axis=1)
        best = np.where(inside, np.maximum(best, np.einsum("kd,kd->k", d, c)), best)
    return best


def braking_capability(lo: NDArray, hi: NDArray) -> NDArray[np.float64]:
    """The deceleration a box guarantees along any direction, ``min(-lo, hi)`` over both axes
    (the inscribed square's half-width); boxes (..., 2)."""
    return np.minimum(-lo, hi).min(axis=-1)


def largest_input(lo: NDArray, hi: NDArray) -> NDArray[np.float64]:
    """The longest input vector of a box, ``|max(|lo|, |hi|)|``; boxes (..., 2)."""
    m = np.maximum(np.abs(lo), np.abs(hi))
    return np.hypot(m[..., 0], m[..., 1])


def box_support(A: NDArray, lo: NDArray, hi: NDArray) -> NDArray:
    """``max_{lo <= u <= hi} A . u`` for rows A (..., 2): the largest value a row can take."""
    m = np.maximum(A * lo, A * hi)
    return m[..., 0] + m[..., 1]  # rows are 2-D: a sum over the last axis costs more
