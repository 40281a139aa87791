"""Planar vectors (..., 2): norms, rotations and the norm clip every controller goes through.

``norm`` is compiled and computes ``sqrt(x * x + y * y)``, the same arithmetic as
``np.linalg.norm(..., axis=-1)`` at a fraction of its call overhead on small arrays.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray


@njit(cache=True)
def norm(u: NDArray[np.float64]) -> NDArray[np.float64]:
    """Euclidean norm of each planar vector of u (..., 2)."""
    return np.sqrt(u[..., 0] * u[..., 0] + u[..., 1] * u[..., 1])


@njit(cache=True)
def _rotate(flat, c, s, out):
    for i in range(flat.shape[0]):
        x, y = flat[i, 0], flat[i, 1]
        out[i, 0] = c[i] * x - s[i] * y
        out[i, 1] = s[i] * x + c[i] * y


def rotate(u: NDArray[np.float64], angle: NDArray[np.float64] | float) -> NDArray[np.float64]:
    """Rotate each row of u (..., 2) counter-clockwise by ``angle`` radians (negative:
    clockwise); ``angle`` is a scalar or broadcasts against u's leading shape."""
    lead = np.shape(u)[:-1]
    c = np.broadcast_to(np.cos(angle), lead).reshape(-1)
    s = np.broadcast_to(np.sin(angle), lead).reshape(-1)
    flat = np.ascontiguousarray(u, dtype=np.float64).reshape(-1, 2)
    out = np.empty_like(flat)
    _rotate(flat, np.ascontiguousarray(c), np.ascontiguousarray(s), out)
    return out.reshape(np.shape(u))


def turn(v: NDArray, cos: NDArray, sin: NDArray) -> NDArray[np.float64]:
    """Vectors (..., 2) turned by the angles of (cos, sin) (broadcast against v's leading
    shape): a body frame's vectors in the world's."""
    return np.stack([cos * v[..., 0] - sin * v[..., 1], sin * v[..., 0] + cos * v[..., 1]], -1)


@njit(cache=True, inline="always")
def clip2(x, y, limit):
    """(x, y) scaled down to norm <= limit, overflow-safe (see ``clip_norm``)."""
    length = np.sqrt(x * x + y * y)
    if not np.isfinite(length):
        # |u|^2 overflowed: scale by the largest component first
        big = max(abs(x), abs(y))
        x, y = x / big, y / big
        length = np.sqrt(x * x + y * y)
    factor = min(1.0, limit / max(length, 1e-300))
    return x * factor, y * factor


@njit(cache=True)
def _clip(flat, limit, scale, out):
    for i in range(flat.shape[0]):
        x, y = clip2(flat[i, 0], flat[i, 1], limit)
        out[i, 0], out[i, 1] = x * scale, y * scale


def as_shape(a: NDArray, shape: tuple[int, ...]) -> NDArray:
    """``a`` broadcast to ``shape`` (no copy when it has that shape already)."""
    return a if a.shape == shape else np.broadcast_to(a, shape)


def as_rows(a: NDArray, shape: tuple[int, ...]) -> NDArray[np.float64]:
    """``a`` broadcast to ``shape`` (..., 2) as contiguous float rows (M, 2)."""
    return np.ascontiguousarray(as_shape(a, shape), dtype=np.float64).reshape(-1, 2)


@njit(cache=True)
def within_distance(x, g, limit):
    dx, dy = x[..., 0] - g[..., 0], x[..., 1] - g[..., 1]
    return np.sqrt(dx * dx + dy * dy) <= limit


def within(
    positions: NDArray[np.float64], targets: NDArray[np.float64], limit: float
) -> NDArray[np.bool_]:
    """(...): whether each row of ``positions`` (..., 2) is within ``limit`` of its target:
    ``norm(positions - targets) <= limit``, the same arithmetic in one compiled pass."""
    return within_distance(positions, as_shape(targets, positions.shape), float(limit))


def clip_each(u: NDArray[np.float64], limit: float | NDArray) -> NDArray[np.float64]:
    """Each agent's row of u (..., N, 2) clipped to its own norm bound: ``limit`` one for all,
    or (N,) one per agent."""
    lim = limit if np.ndim(limit) == 0 else np.asarray(limit)[:, None]
    return clip_norm(u / lim, 1.0) * lim


def clip_norm(u: NDArray[np.float64], limit: float, scale: float = 1.0) -> NDArray[np.float64]:
    """Scale each row of u (..., 2) down to norm <= limit (directions kept), then multiply by
    ``scale``; without overflow: a huge finite row such as (1e200, 0) keeps its direction."""
    flat = np.ascontiguousarray(u, dtype=np.float64).reshape(-1, 2)
    out = np.empty_like(flat)
    _clip(flat, float(limit), float(scale), out)
    return out.reshape(np.shape(u))
