"""The separating direction of two segments in the plane (``docs/double_integrator.md``, "The
stopping-segment barrier"): for convex sets ``A``, ``B`` and any unit ``n``,
``dist(A, B) >= min_{x in A} n.x - max_{y in B} n.y``, with equality at the direction between
their closest points. Two segments of the plane that do not cross have a closest pair with an
endpoint of one of them, so the four endpoint-to-segment distances find it."""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray


@njit(cache=True, inline="always", error_model="numpy")
def _to_segment(x0, x1, s0x, s0y, s1x, s1y):
    """``x`` minus its nearest point of the segment ``[s0, s1]`` (a point when s0 = s1).

    Where that point is inside the segment, the offset is ``x``'s component across the
    segment, along its unit normal: exactly perpendicular to it up to the normal's own
    rounding. Taken as ``x`` minus the nearest point, it carries that point's rounding (the
    segment's length times machine epsilon) in its direction, and the bound along it the
    direction's error times the segment's length: 0.04 m beside a wall 2e7 m long."""
    sx, sy = s1x - s0x, s1y - s0y
    dx, dy = x0 - s0x, x1 - s0y
    L2 = sx * sx + sy * sy
    if L2 > 0.0:
        along = dx * sx + dy * sy
        if along >= L2:
            return x0 - s1x, x1 - s1y
        if along > 0.0:
            L = np.sqrt(L2)
            mx, my = -sy / L, sx / L
            across = dx * mx + dy * my
            return across * mx, across * my
    return dx, dy


@njit(cache=True, inline="always", error_model="numpy")
def separate(a0x, a0y, a1x, a1y, b0x, b0y, b1x, b1y, fx, fy):
    """One pair of segments: ``(n_x, n_y, bound)`` of ``separation``."""
    # the four endpoint-to-segment offsets, each from B toward A; the first smallest wins
    bx, by = _to_segment(a0x, a0y, b0x, b0y, b1x, b1y)
    best = bx * bx + by * by
    cx, cy = _to_segment(a1x, a1y, b0x, b0y, b1x, b1y)
    if cx * cx + cy * cy < best:
        bx, by, best = cx, cy, cx * cx + cy * cy
    cx, cy = _to_segment(b0x, b0y, a0x, a0y, a1x, a1y)
    if cx * cx + cy * cy < best:
        bx, by, best = -cx, -cy, cx * cx + cy * cy
    cx, cy = _to_segment(b1x, b1y, a0x, a0y, a1x, a1y)
    if cx * cx + cy * cy < best:
        bx, by, best = -cx, -cy, cx * cx + cy * cy
    length = np.sqrt(best)
    if length > 0.0:
        nx, ny = bx / length, by / length
    else:
        f = np.sqrt(fx * fx + fy * fy)
        nx, ny = fx / f, fy / f
    lo = min(nx * a0x + ny * a0y, nx * a1x + ny * a1y)
    hi = max(nx * b0x + ny * b0y, nx * b1x + ny * b1y)
    # segments that meet with no direction to part along are 0 apart
    return nx, ny, 0.0 if np.isnan(lo - hi) else lo - hi


@njit(cache=True, error_model="numpy")
def _separation(a0, a1, b0, b1, fallback, n, bound):
    for k in range(len(bound)):
        n[k, 0], n[k, 1], bound[k] = separate(
            a0[k, 0],
            a0[k, 1],
            a1[k, 0],
            a1[k, 1],
            b0[k, 0],
            b0[k, 1],
            b1[k, 0],
            b1[k, 1],
            fallback[k, 0],
            fallback[k, 1],
        )


def separation(
    a0: NDArray, a1: NDArray, b0: NDArray, b1: NDArray, fallback: NDArray
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Unit ``n`` (K, 2) from segment ``B = [b0, b1]`` toward ``A = [a0, a1]`` along their
    closest points, and the bound ``min(n.a0, n.a1) - max(n.b0, n.b1)`` (K,), which is
    ``dist(A, B)`` to rounding when they do not cross and below it when they do. Segments that
    touch take ``fallback`` (a direction, normalised here); where that is 0 too, n is NaN and
    the bound 0."""
    K = len(a0)
    n, bound = np.empty((K, 2)), np.empty(K)
    args = (np.ascontiguousarray(x, dtype=np.float64) for x in (a0, a1, b0, b1, fallback))
    _separation(*args, n, bound)
    return n, bound
