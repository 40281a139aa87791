"""Culling by the nominal action: where the single-integrator QP's solution can lie.

Agent i's QP (paper, eq. ``qp``) is the Euclidean projection of its nominal ``ū`` onto a convex
set C (its box and its rows). When C holds ``u = 0`` (its box does, by construction, and so does
every row with ``b ≥ 0``: every pair not overlapping), the projection ``u*`` satisfies
``(ū − u*)ᵀ(0 − u*) ≤ 0``, that is ``|u* − ū/2| ≤ |ū|/2``: it lies in the disk with diameter
``[0, ū]``, and so does the projection onto any subset of the rows. A row ``aᵀu ≤ b`` with
``b ≥ max over that disk of aᵀu = aᵀū/2 + |a||ū|/2`` then holds at the solution found without
it, which is therefore the solution with it: dropping it changes nothing (``docs/math.md``,
"Culling by the nominal"). The same disk bounds ``|u*| ≤ |ū|``, so an agent's search radius
takes ``min(|ū|, |U|)`` in place of the box's ``|U|``. An agent with a row ``b < 0`` (a pair
already closer than its safe distance) has no such disk; it keeps the box's radius and rows.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env.geometry import pairs
from rsvo_env.geometry.bodies import Bodies
from rsvo_env.qp.rows import Rows, storage
from rsvo_env.responsibility.pair_weights import Floor
from rsvo_env.util import grid, sizes

if TYPE_CHECKING:
    from rsvo_env.filter.config import FilterConfig

# the disk's support is exact only in exact arithmetic: a row this close to it (relative to
# |a| |ū|) stays
MARGIN = 1e-9


def search(
    cfg: FilterConfig,
    positions: NDArray,
    nominal: NDArray,
    floor: Floor,
    scaled_floor: NDArray,
    box_radii: NDArray,
    bodies: Bodies,
    rows_of: Callable,
    likely: NDArray[np.bool_] | None = None,
) -> tuple[NDArray, NDArray, Rows, Any, NDArray, NDArray[np.bool_]]:
    """The large-N pair search by the nominal: each agent searches within the radius of
    ``min(|ū|, |U|)`` (E, N, K, from ``floor``) and keeps a pair where a side's row can bind
    within its disk at its floor's weight (``scaled_floor``: the floors times gamma). An agent
    in a pair closer than its safe distance (every such pair is within that radius), or with
    an obstacle row ``b < 0``, is exempt: it keeps every pair within its box's radius
    (``box_radii``). The agents ``likely`` (M,) to be (the last call's exempt: a jam stays
    jammed) search so at once; any other exempt agent adds its pairs after. Whatever
    ``likely`` holds, the rows that can bind are found. ``rows_of(I, J)`` builds the rows and
    the obstacles' barrier values. Returns the pairs, the rows, the obstacles' barrier
    values, each scene's smallest search radius and the exempt agents (M,)."""
    E, n = positions.shape[:2]
    M = E * n
    boxed = np.zeros(M, dtype=np.bool_) if likely is None else likely
    speed = speeds(nominal, bodies)
    radii = cfg.model.culling_radii(cfg, floor[0], None, bodies, speed)
    searched = np.where(boxed.reshape(E, n, 1), box_radii, radii) if boxed.any() else radii
    disk = (nominal, scaled_floor, bodies.reach(E, n), boxed.reshape(E, n))
    I, J = pairs.pairs_within_agent_radii(positions, searched, floor, disk)
    # too close, if only by rounding: a superset of the agents with a pair row b < 0
    exempt = too_close(positions.reshape(M, 2), I, J, bodies.radii)
    late = exempt & ~boxed
    if late.any():
        I, J = box_pairs(positions, box_radii, floor[1], late, I, J)
    rows, obstacle_h = rows_of(I, J)
    late = negative_rows(rows.offsets, rows.flat_b) & ~exempt & ~boxed
    if late.any():  # an obstacle row b < 0
        exempt |= late
        I, J = box_pairs(positions, box_radii, floor[1], late, I, J)
        rows, obstacle_h = rows_of(I, J)
    reach = smallest_radius(radii, box_radii, (exempt | boxed).reshape(E, n))
    return I, J, rows, obstacle_h, reach, exempt


def speeds(nominal: NDArray[np.float64], bodies: Bodies) -> NDArray[np.float64]:
    """(E, N) the largest norm each agent's solution can have while its set holds 0:
    ``min(|ū|, |U|)``, ``U`` its box's largest input vector."""
    E, n = nominal.shape[:2]
    return _speeds(np.ascontiguousarray(nominal, dtype=np.float64), bodies.speed.reshape(E, n))


@njit(cache=True)
def _speeds(nominal, box_speed):
    E, n = box_speed.shape
    out = np.empty((E, n))
    for e in range(E):
        for i in range(n):
            x, y = nominal[e, i, 0], nominal[e, i, 1]
            out[e, i] = min(np.sqrt(x * x + y * y), box_speed[e, i])
    return out


def box_pairs(
    positions: NDArray,
    box_radii: NDArray,
    group: NDArray,
    exempt: NDArray[np.bool_],
    I: NDArray[np.int64],
    J: NDArray[np.int64],
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """The pairs (I, J) (sorted) with those of each ``exempt`` agent (M,) within its box's
    radius against the other's group (``box_radii`` (E, N, K)) added, sorted."""
    E, n = positions.shape[:2]
    x = np.ascontiguousarray(positions, dtype=np.float64)
    who = np.flatnonzero(exempt)
    if len(who) <= sizes.EXEMPT_SCAN_MAX_AGENTS:
        I2, J2 = _scan(x, who, np.ascontiguousarray(box_radii), group)
    else:  # many: the grid, each agent but the exempt searching nothing
        radii = np.where(exempt.reshape(E, n)[..., None], box_radii, 0.0)
        I2, J2 = grid.pairs_within_radii(x, radii, group)
    return _union(I, J, I2, J2)


@njit(cache=True)
def _scan(x, who, radius, group):
    """Pairs (i < j, flat, sorted) of the agents ``who`` (flat, increasing) with every agent of
    their env within their radius against its group: a scan of the env per agent."""
    n = x.shape[1]
    hit = np.zeros((who.shape[0], n), dtype=np.bool_)
    for q in range(who.shape[0]):
        e, i = who[q] // n, who[q] % n
        for j in range(n):
            dx, dy = x[e, i, 0] - x[e, j, 0], x[e, i, 1] - x[e, j, 1]
            r = radius[e, i, group[e, j]]
            hit[q, j] = j != i and dx * dx + dy * dy <= r * r
    c = hit.sum()
    I = np.empty(c, dtype=np.int64)
    J = np.empty(c, dtype=np.int64)
    c = 0
    for q in range(who.shape[0]):
        e, i = who[q] // n, who[q] % n
        for j in range(n):
            if hit[q, j]:
                I[c], J[c] = e * n + min(i, j), e * n + max(i, j)
                c += 1
    order = np.argsort(I * (x.shape[0] * n) + J)
    return I[order], J[order]


@njit(cache=True)
def _union(I1, J1, I2, J2):
    """The union of two sorted lists of pairs, sorted, each pair once."""
    P1, P2 = I1.shape[0], I2.shape[0]
    I = np.empty(P1 + P2, dtype=np.int64)
    J = np.empty(P1 + P2, dtype=np.int64)
    a = b = c = 0
    while a < P1 or b < P2:
        if b == P2 or (a < P1 and (I1[a] < I2[b] or (I1[a] == I2[b] and J1[a] < J2[b]))):
            I[c], J[c] = I1[a], J1[a]
            a += 1
        else:
            I[c], J[c] = I2[b], J2[b]
            if a < P1 and I1[a] == I2[b] and J1[a] == J2[b]:
                a += 1
            b += 1
        if c == 0 or I[c] != I[c - 1] or J[c] != J[c - 1]:
            c += 1
    return I[:c], J[:c]


@njit(cache=True)
def smallest_radius(radii, box_radii, exempt):
    """(E,) each scene's smallest positive search radius (E, N, K), the box's for the
    ``exempt`` agents (E, N): every pair closer than it was examined."""
    E, n, K = radii.shape
    out = np.full(E, np.inf)
    for e in range(E):
        for i in range(n):
            for k in range(K):
                r = box_radii[e, i, k] if exempt[e, i] else radii[e, i, k]
                if r > 0.0:
                    out[e] = min(out[e], r)
    return out


@njit(cache=True)
def too_close(x, I, J, radii):
    """(M,) whether each agent is in a pair (I, J) with ``h < 0``, computed as its row's
    ``h`` is (``single_integrator.single_integrator_row``): every agent with a pair row
    ``b < 0``."""
    out = np.zeros(x.shape[0], dtype=np.bool_)
    for p in range(I.shape[0]):
        i, j = I[p], J[p]
        R = radii[i] + radii[j]
        dx, dy = x[i, 0] - x[j, 0], x[i, 1] - x[j, 1]
        if (dx * dx + dy * dy) - R * R < 0.0:
            out[i] = out[j] = True
    return out


@njit(cache=True)
def negative_rows(offsets, b):
    """(M,) whether each agent has a row with ``b < 0`` (its set may not hold 0)."""
    M = offsets.shape[0] - 1
    out = np.zeros(M, dtype=np.bool_)
    for i in range(M):
        for k in range(offsets[i], offsets[i + 1]):
            if b[k] < 0.0:
                out[i] = True
                break
    return out


def cull(rows: Rows, nominal: NDArray[np.float64], exempt: NDArray[np.bool_]) -> Rows:
    """``rows`` without the rows that cannot bind within their agent's disk ``[0, ū]``
    (``nominal`` (M, 2)); the ``exempt`` agents (M,) keep all theirs."""
    keep = _keep(rows.offsets, rows.flat_A, rows.flat_b, nominal, exempt)
    offsets, A, b, hh, nb, un, cp = _compact(
        rows.offsets,
        keep,
        rows.flat_A,
        rows.flat_b,
        rows.flat_h,
        rows.flat_neighbor,
        rows.flat_unrecoverable,
        rows.flat_capped,
    )
    return replace(
        rows,
        flat_A=A,
        flat_b=b,
        offsets=offsets,
        flat_neighbor=nb,
        flat_h=hh,
        flat_unrecoverable=un,
        flat_capped=cp,
        n_culled=rows.n_culled + len(keep) - len(b),
    )


@njit(cache=True, inline="always")
def disk_support(ax, ay, ux, uy, s):
    """``max aᵀu`` over the disk with diameter ``[0, ū]`` (``s = |ū|``), widened by
    ``MARGIN |a| s``: a row ``aᵀu <= b`` can bind there only if ``b`` is below it."""
    reach = np.sqrt(ax * ax + ay * ay) * s
    return 0.5 * (ax * ux + ay * uy + reach) + MARGIN * reach


@njit(cache=True)
def _keep(offsets, A, b, nominal, exempt):
    """Per row: whether it can bind within its agent's disk (always, for an exempt agent)."""
    keep = np.ones(b.shape[0], dtype=np.bool_)
    for i in range(offsets.shape[0] - 1):
        if exempt[i]:
            continue
        ux, uy = nominal[i, 0], nominal[i, 1]
        s = np.sqrt(ux * ux + uy * uy)
        for k in range(offsets[i], offsets[i + 1]):
            keep[k] = b[k] < disk_support(A[k, 0], A[k, 1], ux, uy, s)
    return keep


@njit(cache=True)
def _compact(offsets, keep, A, b, h, nb, un, cp):
    """The kept rows, stored by agent as before (CSR)."""
    M = offsets.shape[0] - 1
    out_offsets = np.zeros(M + 1, dtype=np.int64)
    for i in range(M):
        c = 0
        for k in range(offsets[i], offsets[i + 1]):
            c += keep[k]
        out_offsets[i + 1] = out_offsets[i] + c
    A2, b2, h2, nb2, un2, cp2 = storage(out_offsets[M])
    q = 0
    for k in range(b.shape[0]):
        if keep[k]:
            A2[q, 0], A2[q, 1], b2[q], h2[q], nb2[q] = A[k, 0], A[k, 1], b[k], h[k], nb[k]
            un2[q], cp2[q] = un[k], cp[k]
            q += 1
    return out_offsets, A2, b2, h2, nb2, un2, cp2
