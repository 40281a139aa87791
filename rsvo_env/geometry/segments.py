"""The separating direction of two segments in the plane (``docs/double_integrator.md``, "The
stopping-segment barrier"): for convex sets ``A``, ``B`` and any unit ``n``,
``dist(A, B) >= min_{x in A} n.x - max_{y in B} n.y``, with equality at the direction between
their closest points. Two segments of the plane that do not cross have a closest pair with an
endpoint of one of them, so the four endpoint-to-segment distances find it."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def _to_segment(x: NDArray, s0: NDArray, s1: NDArray) -> NDArray[np.float64]:
    """``x`` minus its nearest point of the segment ``[s0, s1]`` (a point when s0 = s1)."""
    e = s1 - s0
    L2 = (e * e).sum(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(L2 > 0, ((x - s0) * e).sum(axis=-1) / L2, 0.0)
    return x - s0 - np.clip(t, 0.0, 1.0)[..., None] * e


def separation(
    a0: NDArray, a1: NDArray, b0: NDArray, b1: NDArray, fallback: NDArray
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Unit ``n`` (K, 2) from segment ``B = [b0, b1]`` toward ``A = [a0, a1]`` along their
    closest points, and the bound ``min(n.a0, n.a1) - max(n.b0, n.b1)`` (K,), which is
    ``dist(A, B)`` to rounding when they do not cross and below it when they do. Segments that
    touch take ``fallback`` (a direction, normalised here); where that is 0 too, n is NaN and
    the bound 0."""
    cand = np.stack(
        [
            _to_segment(a0, b0, b1),
            _to_segment(a1, b0, b1),
            -_to_segment(b0, a0, a1),
            -_to_segment(b1, a0, a1),
        ]
    )
    d2 = (cand * cand).sum(axis=-1)
    best = np.take_along_axis(cand, d2.argmin(axis=0)[None, :, None], axis=0)[0]
    length = np.sqrt((best * best).sum(axis=-1))
    f_len = np.sqrt((fallback * fallback).sum(axis=-1))
    with np.errstate(divide="ignore", invalid="ignore"):
        n = np.where((length > 0)[:, None], best / length[:, None], fallback / f_len[:, None])
    dot = lambda x: (n * x).sum(axis=-1)  # noqa: E731
    bound = np.minimum(dot(a0), dot(a1)) - np.maximum(dot(b0), dot(b1))
    # segments that meet with no direction to part along are 0 apart
    return n, np.where(np.isnan(bound), 0.0, bound)
