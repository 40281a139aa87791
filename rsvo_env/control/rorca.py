"""R-ORCA: ORCA's reciprocal half-planes with the R-SVO weights in place of its fixed one-half
split, as an active nominal controller for single integrators (``docs/liveness.md``).

ORCA (van den Berg et al., 2011) gives agent i, for each neighbour j within ``neighbor_dist``,
the smallest change ``u`` of the relative velocity that leaves the truncated velocity obstacle
(horizon ``tau``), and asks i to take half of it: the half-plane of velocities v with
``(v - (v_i + u / 2)) . n >= 0`` (``n`` the outward normal). Here agent i takes the share
``1 - omega_ij`` of ``u`` where it is avoidance (the relative velocity inside the obstacle) and
``omega_ij`` where it is slack (outside, ``u`` the room left to close), eq. ``rorca``: the egoist
(larger omega) does less of the avoidance and gets more of the slack, as the filter's rows give
it, and ``omega = 1/2`` is ORCA. Unlike a filter's rows these are *active*: an agent parked on
its goal whose velocity obstacle holds 0 must step aside, which is what makes crowds finish.
The velocity is the one closest to the preferred velocity within the half-planes and the speed
limit (an octagon inscribed in the disk), solved exactly by ``rsvo_env.qp.exact``; an
empty polygon gives the least-violating velocity (ORCA's third linear program). The R-CBF
filter on top keeps the guarantee whatever this controller proposes.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env.geometry import pairs
from rsvo_env.qp import exact
from rsvo_env.responsibility.svo import Weighting
from rsvo_env.util.planar import clip_norm, norm

# below this fraction of its preferred speed an agent counts as held still (it sidesteps)
SIDESTEP = 0.0625
# near its goal, where its look-ahead passes the goal and reaches a neighbour's body, an agent
# that has come no closer to its goal for HOLD_SECONDS prefers at most ARRIVE times its goal
# distance per horizon tau: held for tau, as the half-planes assume, its preferred velocity then
# ends at most one goal distance past the goal. Faster (move-to-goal's k = 2 with tau = 2 runs 4
# goal distances), agents parked beyond the goal fill the look-ahead and an agent can orbit its
# goal for good; an agent still closing in keeps its speed (docs/liveness.md)
ARRIVE = 2.0
HOLD_SECONDS = 0.3
_OCTAGON = np.stack(
    [np.cos(np.arange(8) * np.pi / 4), np.sin(np.arange(8) * np.pi / 4)], axis=-1
)


@njit(cache=True)
def _half_planes(x, v, radii, I, J, share, tau, dt, parked, seen):
    """Both directed half-planes of each pair (I, J): rows ``A . v <= b`` for agent I (first
    P) and agent J (last P), ``share`` (P, 2) each side's part of the avoidance (summing to 1;
    of the slack each side takes the other's share). An agent ``parked`` (M,) reads a neighbour
    en route at the velocity ``seen`` (M, 2) instead of its current one."""
    P = I.shape[0]
    A = np.empty((2 * P, 2))
    b = np.empty(2 * P)
    inv_tau = 1.0 / tau
    for p in range(P):
        i, j = I[p], J[p]
        for side in range(2):
            me, other = (i, j) if side == 0 else (j, i)
            rx, ry = x[other, 0] - x[me, 0], x[other, 1] - x[me, 1]
            vo = seen[other] if parked[me] and not parked[other] else v[other]
            wx0, wy0 = v[me, 0] - vo[0], v[me, 1] - vo[1]
            R = radii[me] + radii[other]
            d2, R2 = rx * rx + ry * ry, R * R
            if d2 > R2:
                wx, wy = wx0 - inv_tau * rx, wy0 - inv_tau * ry
                w2 = wx * wx + wy * wy
                dot1 = wx * rx + wy * ry
                if dot1 < 0.0 and dot1 * dot1 > R2 * w2:  # the cutoff circle
                    wl = np.sqrt(w2)
                    ux, uy = wx / wl, wy / wl
                    dx, dy = uy, -ux
                    s = R * inv_tau - wl
                    cx, cy = s * ux, s * uy
                else:  # a leg
                    leg = np.sqrt(d2 - R2)
                    if rx * wy - ry * wx > 0.0:
                        dx, dy = (rx * leg - ry * R) / d2, (rx * R + ry * leg) / d2
                    else:
                        dx, dy = -(rx * leg + ry * R) / d2, -(-rx * R + ry * leg) / d2
                    dot2 = wx0 * dx + wy0 * dy
                    cx, cy = dot2 * dx - wx0, dot2 * dy - wy0
            else:  # overlapping: leave within one step
                wx, wy = wx0 - rx / dt, wy0 - ry / dt
                wl = np.sqrt(wx * wx + wy * wy)
                ux, uy = (wx / wl, wy / wl) if wl > 0.0 else (1.0, 0.0)
                dx, dy = uy, -ux
                s = R / dt - wl
                cx, cy = s * ux, s * uy
            # A . u > 0 (A the row below): the current velocity already meets the row, and u is
            # room left to close (slack), not avoidance
            sh = share[p, side] if dy * cx - dx * cy <= 0.0 else share[p, 1 - side]
            px, py = v[me, 0] + sh * cx, v[me, 1] + sh * cy
            k = p + side * P
            # the half-plane det(d, point - v) <= 0 as a row
            A[k, 0], A[k, 1] = dy, -dx
            b[k] = dy * px - dx * py
    return A, b


@njit(cache=True)
def _goal_clearance(x, g, r, I, J, out):
    """``out[i]``: the smallest gap between agent i's goal and a listed neighbour's body."""
    out[:] = np.inf
    for p in range(I.shape[0]):
        i, j = I[p], J[p]
        for a, b in ((i, j), (j, i)):
            dx, dy = g[a, 0] - x[b, 0], g[a, 1] - x[b, 1]
            out[a] = min(out[a], np.sqrt(dx * dx + dy * dy) - r[a] - r[b])


def arrival_capped(
    preferred: NDArray, positions: NDArray, goals: NDArray, radii: NDArray, tau: float,
    I: NDArray[np.int64], J: NDArray[np.int64], held: NDArray[np.bool_] | None = None,
) -> NDArray[np.float64]:  # fmt: skip
    """``preferred`` (M, 2) scaled down to speed at most ``ARRIVE |goal - x| / tau`` where the
    look-ahead ``|preferred| tau`` passes the goal by more than the gap between the goal and a
    neighbour's body (pairs I, J; flat (M, 2) positions and goals, radii (M,)); with ``held``
    (M,), only there."""
    gap = np.empty(len(positions))
    _goal_clearance(positions, goals, radii, I, J, gap)
    speed, dist = norm(preferred), norm(goals - positions)
    over = (speed * tau - dist > gap) & (speed * tau > ARRIVE * dist)
    if held is not None:
        over &= held
    scale = np.where(over, ARRIVE * dist / (tau * np.where(over, speed, 1.0)), 1.0)
    return preferred * scale[:, None]


class Rules(NamedTuple):
    """The state R-ORCA's rules read beyond the crowd's motion: ``parked`` (E, N) agents at
    their goals, ``goals`` (E, N, 2), ``held`` (E, N) agents held short of them."""

    parked: NDArray | None = None
    goals: NDArray | None = None
    held: NDArray | None = None


def rorca_velocities(
    positions: NDArray,
    velocities: NDArray,
    preferred: NDArray,
    radii: NDArray,
    theta: NDArray,
    modes: list[Weighting],
    u_max: float,
    dt: float,
    tau: float = 2.0,
    neighbor_dist: float | None = None,
    max_neighbors: int | None = 10,
    rules: Rules | None = None,
) -> NDArray[np.float64]:
    """Eq. ``rorca``: each agent's velocity (E, N, 2) closest to ``preferred`` within its R-ORCA
    half-planes against the nearest ``max_neighbors`` (None: all) of the neighbours within
    ``neighbor_dist`` (default ``5 (r_i + r_j)`` of the largest pair), and the speed limit
    ``u_max`` (ORCA's defaults: 10 neighbours, 5 pair distances, horizon 2 s). ``radii``
    (E, N) or (N,); the weights come from the scores ``theta`` (E, N) and each env's weighting
    ``modes`` (``"symmetric"``: ORCA); ``parked`` (E, N): agents at their goals, which take all
    of the avoidance and none of the slack from agents en route, read at their preferred
    velocities; ``goals`` (E, N, 2): near its goal, where its look-ahead reaches a neighbour, an
    agent's preferred speed is capped (:func:`arrival_capped`), only the agents ``held`` (E, N)
    if given; these three are ``rules`` (:class:`Rules`, None: none of them)."""
    parked, goals, held = (None, None, None) if rules is None else rules
    E, n = positions.shape[:2]
    radii = np.broadcast_to(radii, (E, n))
    if neighbor_dist is None:
        neighbor_dist = 10.0 * float(radii.max())
    I, J = pairs.candidate_pairs(positions, neighbor_dist)
    w = pairs.weights_of(theta, modes, I, J)
    x = positions.reshape(E * n, 2)
    v = velocities.reshape(E * n, 2)
    M = E * n
    share = 1.0 - w
    park = np.zeros(M, dtype=np.bool_)
    if parked is not None:
        # an agent parked on its goal takes all of the avoidance from one en route, reading it
        # at its preferred velocity so as to step aside before it is pushed: an egoist at rest
        # would otherwise stand as a wall (the shares still sum to 1)
        park = np.ascontiguousarray(parked).reshape(-1)
        s = share[:, 0]
        s = np.where(park[I] & ~park[J], 1.0, np.where(park[J] & ~park[I], 0.0, s))
        share = np.stack([s, 1.0 - s], axis=1)
    r = np.ascontiguousarray(radii).reshape(-1)
    pref = preferred.reshape(M, 2)
    if goals is not None:
        hold = None if held is None else np.ascontiguousarray(held).reshape(-1)
        pref = arrival_capped(pref, x, goals.reshape(M, 2), r, tau, I, J, hold)
    A, b = _half_planes(x, v, r, I, J, share, float(tau), float(dt), park,
                        np.ascontiguousarray(pref, dtype=np.float64))  # fmt: skip
    owner = np.concatenate([I, J])
    if max_neighbors is not None and len(owner):
        # ORCA's neighbour rule: each agent's nearest max_neighbors within neighbor_dist
        d2 = ((x[I] - x[J]) ** 2).sum(axis=-1)
        by = np.lexsort((np.concatenate([d2, d2]), owner))
        first = np.searchsorted(owner[by], owner[by], side="left")
        keep = np.zeros(len(owner), dtype=bool)
        keep[by] = np.arange(len(by)) - first < max_neighbors
        owner, A, b = owner[keep], A[keep], b[keep]
    owner = np.concatenate([owner, np.repeat(np.arange(M), 8)])
    A = np.concatenate([A, np.tile(_OCTAGON, (M, 1))])
    b = np.concatenate([b, np.full(8 * M, u_max * np.cos(np.pi / 8))])
    order = np.argsort(owner, kind="stable")
    offsets = np.zeros(M + 1, dtype=np.int64)
    offsets[1:] = np.cumsum(np.bincount(owner, minlength=M))
    box = np.array([u_max, u_max])
    rows = (A[order], b[order], offsets, -box, box)
    out = exact.solve_csr(pref, *rows)[0]
    # an agent the half-planes hold still while it wants to move (a jam that is symmetric, as
    # in a ring around a common goal) sidesteps: the velocity closest to its preferred one
    # turned to its right, which the half-planes of touching neighbours let it take
    speed = np.sqrt((pref * pref).sum(axis=-1))
    held = np.sqrt((out * out).sum(axis=-1)) < SIDESTEP * speed
    if held.any():
        right = np.stack([pref[:, 1], -pref[:, 0]], axis=-1)
        out = np.where(held[:, None], exact.solve_csr(right, *rows)[0], out)
    # where the half-planes leave no room the least-violating point may lie past the octagon
    # (its rows are relaxed too): the speed limit holds regardless
    return clip_norm(out, u_max).reshape(E, n, 2)
