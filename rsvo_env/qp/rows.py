"""The constraint rows of every agent's QP, stored by agent without padding (CSR): agent i's
rows are ``A[offsets[i]:offsets[i + 1]]``, in pair order. Memory follows the rows kept, not the
widest agent times N: one altruist that keeps a row against every agent of a crowd of 10,000
costs 10,000 rows, not 10,000 x 10,000 padded slots.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray


@njit(cache=True, inline="always")
def support(ax, ay, lo0, lo1, hi0, hi1):
    """``max_{lo <= u <= hi} (ax, ay) . u``: the largest value a row takes over the box."""
    return max(ax * lo0, ax * hi0) + max(ay * lo1, ay * hi1)


@dataclass(frozen=True)
class Rows:
    """Agent i's rows are ``A[k] . u <= b[k]`` for k in ``offsets[i]:offsets[i + 1]``.

    ``neighbor[k]`` is the other agent of row k, ``h[k]`` the pair's barrier value; ``pair_h``
    holds the barrier value of every pair examined, culled or not, in pair order.
    Double-integrator diagnostics: ``unrecoverable`` and ``capped`` per row. ``padded``
    gives the same rows as (n, K) arrays with a mask, for inspection.
    """

    flat_A: NDArray[np.float64]
    flat_b: NDArray[np.float64]
    offsets: NDArray[np.int64]
    flat_neighbor: NDArray[np.int64]
    flat_h: NDArray[np.float64]
    pair_h: NDArray[np.float64]
    flat_unrecoverable: NDArray[np.bool_]
    flat_capped: NDArray[np.bool_]
    n_pairs: int
    n_culled: int

    @property
    def counts(self) -> NDArray[np.int64]:
        """Rows of each agent (n,)."""
        return np.diff(self.offsets)

    @property
    def owner(self) -> NDArray[np.int64]:
        """The agent of each row (R,)."""
        return np.repeat(np.arange(len(self.offsets) - 1), self.counts)

    def padded(self, field: str) -> NDArray:
        """Field ``A``, ``b``, ``mask``, ``neighbor``, ``h``, ``unrecoverable`` or ``capped`` as
        (n, K, ...) with K the most rows of any agent (padding: 0, False, -1)."""
        counts = self.counts
        n, K = len(counts), max(int(counts.max(initial=0)), 1)
        slot = np.arange(len(self.flat_b)) - np.repeat(self.offsets[:-1], counts)
        owner = self.owner
        if field == "mask":
            out = np.zeros((n, K), dtype=bool)
            out[owner, slot] = True
            return out
        flat = getattr(self, f"flat_{field}")
        fill = -1 if field == "neighbor" else 0
        out = np.full((n, K, *flat.shape[1:]), fill, dtype=flat.dtype)
        out[owner, slot] = flat
        return out

    # the padded views, by the names of the padded layout
    A = property(lambda self: self.padded("A"))
    b = property(lambda self: self.padded("b"))
    mask = property(lambda self: self.padded("mask"))
    neighbor = property(lambda self: self.padded("neighbor"))
    h = property(lambda self: self.padded("h"))
    unrecoverable = property(lambda self: self.padded("unrecoverable"))
    capped = property(lambda self: self.padded("capped"))


@njit(cache=True)
def storage(R):
    """Room for R rows: A (R, 2), b, h (R,), neighbour (R,), and the two flags (R,), False."""
    return (
        np.empty((R, 2)),
        np.empty(R),
        np.empty(R),
        np.empty(R, dtype=np.int64),
        np.zeros(R, dtype=np.bool_),
        np.zeros(R, dtype=np.bool_),
    )


@njit(cache=True)
def pack(n, I, J, A_i, b_i, b_j, h, exists, unrec, capped, lo, hi, cull):
    """Directed rows of both agents of each pair, culled and stored by agent in two O(P)
    passes. Pair p gives agent I[p] the row (A_i[p], b_i[p]) and agent J[p] the row
    (-A_i[p], b_j[p]), in pair order, so the result depends on nothing but the inputs."""
    P = I.shape[0]
    keep = np.zeros((P, 2), dtype=np.bool_)
    offsets = np.zeros(n + 1, dtype=np.int64)
    for p in range(P):
        if not exists[p]:
            continue
        ax = A_i[p, 0]
        ay = A_i[p, 1]
        i, j = I[p], J[p]
        # box support of +A_i over agent I's box and of -A_i over agent J's
        if not cull or b_i[p] < support(ax, ay, lo[i, 0], lo[i, 1], hi[i, 0], hi[i, 1]):
            keep[p, 0] = True
            offsets[i + 1] += 1
        if not cull or b_j[p] < support(-ax, -ay, lo[j, 0], lo[j, 1], hi[j, 0], hi[j, 1]):
            keep[p, 1] = True
            offsets[j + 1] += 1
    for i in range(n):
        offsets[i + 1] += offsets[i]
    A, b, hh, nb, un, cp = storage(offsets[n])
    fill = offsets[:-1].copy()
    for p in range(P):
        for side in range(2):
            if not keep[p, side]:
                continue
            if side == 0:
                o, other, sign, rhs = I[p], J[p], 1.0, b_i[p]
            else:
                o, other, sign, rhs = J[p], I[p], -1.0, b_j[p]
            k = fill[o]
            fill[o] += 1
            A[k, 0] = sign * A_i[p, 0]
            A[k, 1] = sign * A_i[p, 1]
            b[k] = rhs
            hh[k] = h[p]
            nb[k] = other
            un[k] = unrec[p]
            cp[k] = capped[p]
    return A, b, offsets, nb, hh, un, cp


class PairFlags(NamedTuple):
    """Per pair (P,): whether it has rows, whether it is unrecoverable (each agent takes half
    of the budget), whether its share was capped to what the agent can do."""

    exists: NDArray
    unrecoverable: NDArray
    capped: NDArray


def finish(
    n: int,
    I: NDArray,
    J: NDArray,
    A_i: NDArray,
    b_i: NDArray,
    b_j: NDArray,
    h: NDArray,
    lo: NDArray,
    hi: NDArray,
    flags: PairFlags,
    cull: bool = True,
) -> Rows:
    """Both agents' rows of each pair, exact culling, storage by agent (``flags``: which pairs
    have rows, and which of those are unrecoverable or capped).

    Culling (``docs/math.md``): a row whose right side is at least the largest value its left
    side takes over its agent's box cannot bind anywhere in that box, so dropping it changes no
    solution. ``lo``, ``hi``: one box (2,) or one per agent (n, 2).
    """
    exists, unrecoverable, capped = flags
    lo, hi = (np.ascontiguousarray(np.broadcast_to(x, (n, 2)), dtype=np.float64) for x in (lo, hi))
    A, b, offsets, nb, hh, un, cp = pack(
        n,
        I,
        J,
        np.ascontiguousarray(A_i),
        b_i,
        b_j,
        h,
        exists,
        unrecoverable,
        capped,
        lo,
        hi,
        cull,
    )
    return Rows(
        flat_A=A,
        flat_b=b,
        offsets=offsets,
        flat_neighbor=nb,
        flat_h=hh,
        pair_h=h,
        flat_unrecoverable=un,
        flat_capped=cp,
        n_pairs=len(I),
        n_culled=2 * int(exists.sum()) - len(b),
    )


@njit(cache=True)
def _interleave(off1, A1, b1, h1, nb1, un1, cp1, off2, A2, b2, h2, nb2):
    """Agent by agent: its rows of set 1, then those of set 2 (no flags)."""
    n = off1.shape[0] - 1
    offsets = off1 + off2
    A, b, hh, nb, un, cp = storage(offsets[n])
    for i in range(n):
        k = offsets[i]
        for src in range(off1[i], off1[i + 1]):
            A[k, 0], A[k, 1], b[k], hh[k], nb[k] = (
                A1[src, 0],
                A1[src, 1],
                b1[src],
                h1[src],
                nb1[src],
            )
            un[k], cp[k] = un1[src], cp1[src]
            k += 1
        for src in range(off2[i], off2[i + 1]):
            A[k, 0], A[k, 1], b[k], hh[k], nb[k] = (
                A2[src, 0],
                A2[src, 1],
                b2[src],
                h2[src],
                nb2[src],
            )
            k += 1
    return offsets, A, b, hh, nb, un, cp


def with_obstacles(
    rows: Rows, offsets: NDArray, A: NDArray, b: NDArray, h: NDArray, obstacle: NDArray
) -> Rows:
    """``rows`` with each agent's obstacle rows after its pair rows; an obstacle row's
    ``neighbor`` is ``-1 - o`` for obstacle o (agents are >= 0)."""
    off, A_, b_, hh, nb, un, cp = _interleave(
        rows.offsets,
        rows.flat_A,
        rows.flat_b,
        rows.flat_h,
        rows.flat_neighbor,
        rows.flat_unrecoverable,
        rows.flat_capped,
        offsets,
        A,
        b,
        h,
        -1 - obstacle,
    )
    return replace(
        rows,
        flat_A=A_,
        flat_b=b_,
        offsets=off,
        flat_neighbor=nb,
        flat_h=hh,
        flat_unrecoverable=un,
        flat_capped=cp,
    )
