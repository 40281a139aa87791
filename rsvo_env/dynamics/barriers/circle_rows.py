"""Double-integrator rows against static circular obstacles (``docs/obstacles.md``): a circle is
a neighbour that never moves and takes no responsibility, so the pair's rows
(``docs/double_integrator.md``) hold with ``dp = p_i - c``, ``dv = v_i``, ``Ds = r_i + rho``,
the braking capability of agent i alone (``A = a_max``, not ``2 a_max``), the whole RHS agent
i's and no capability on the obstacle's side. Full braking (``a_i = a_max dp / |dp|``, in the
box) meets every row of one obstacle while ``h >= 0``, the sampled-data row and the tangential
row of the nearly head-on window included, so with one active obstacle (and no neighbour) the QP
is feasible, as for one pair.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from rsvo_env.dynamics.barriers.box import (
    box_support,
    braking_capability,
    largest_input,
    support_within,
)
from rsvo_env.dynamics.barriers.pair_rows import braking_rhs

if TYPE_CHECKING:
    from rsvo_env.geometry.bodies import Bodies
    from rsvo_env.util.settings import FilterSettings


def double_integrator_obstacle_rows(
    cfg: FilterSettings,
    positions: NDArray,
    velocities: NDArray,
    bodies: Bodies,
    capsules: NDArray,
    n: int,
) -> tuple[NDArray, ...]:
    """Every agent's rows against every circle of its env, culled against its box, stored by
    agent: offsets (M + 1,), A (R, 2), b (R,), h (R,), the obstacle of each row, and each
    agent's smallest h (M,). ``capsules`` (E, O, 5) or (1, O, 5), circles only."""
    M = len(positions)
    caps = (
        capsules
        if capsules.shape[0] > 1
        else np.broadcast_to(capsules, (M // n, *capsules.shape[1:]))
    )
    env = np.arange(M) // n
    centre = caps[env, :, 0:2]  # (M, O, 2)
    O = centre.shape[1]
    dp = (positions[:, None, :] - centre).reshape(-1, 2)
    dv = np.repeat(velocities, O, axis=0)
    agent = np.repeat(np.arange(M), O)
    Ds = (bodies.radii[:, None] + caps[env, :, 4]).reshape(-1)
    # each row's box: the config's, or its agent's own
    lo, hi = (cfg.lo, cfg.hi) if bodies.uniform else (bodies.lo[agent], bodies.hi[agent])
    dist = np.linalg.norm(dp, axis=1)
    dpdv = np.einsum("ij,ij->i", dp, dv)
    dv2 = np.einsum("ij,ij->i", dv, dv)
    gamma, dt = cfg.gamma, cfg.dt
    push = box_support(dp, lo, hi)
    A_i = -dp
    tangential = None
    if cfg.barrier == "braking":
        A = braking_capability(lo, hi)  # agent i brakes alone
        U = largest_input(lo, hi)
        q, h, rhs, exists, k = braking_rhs(dist, dpdv, dv2, Ds, A, U, gamma, dt, push)
        if len(k):  # the nearly head-on window: the tangential row, agent i's whole share
            wt = np.sqrt(np.maximum(dv2[k] - q[k] ** 2, 0.0))
            e_t = (dv[k] - q[k, None] * dp[k] / dist[k, None]) / wt[:, None]
            A_t, s_t = -dist[k, None] * e_t, dist[k] * wt / dt
            push[k] = support_within(
                dp[k], lo if bodies.uniform else lo[k], hi if bodies.uniform else hi[k], A_t, s_t
            )
            tangential = (k, A_t, s_t)
    else:
        g2 = gamma if cfg.gamma2 is None else cfg.gamma2
        h = dist * dist - Ds**2
        rhs = 2.0 * dv2 + 2.0 * (gamma + g2) * dpdv + gamma * g2 * h
        A_i, push = -2.0 * dp, 2.0 * push
        exists = np.ones(len(dist), dtype=bool)
    # a body at the centre has no direction to keep away along: a row no action meets
    bad = (dist == 0.0) | (exists & ~np.isfinite(rhs))
    A_i = np.where(bad[:, None], 0.0, A_i)
    rhs = np.where(bad, -1.0, rhs)
    h = np.where(bad, -Ds, h)
    keep = (exists | bad) & (rhs < push)  # else the row cannot bind over the box
    rows = [(agent[keep], A_i[keep], rhs[keep], h[keep], np.nonzero(keep)[0] % O)]
    if tangential is not None:
        k, A_t, s_t = tangential
        rows.append((agent[k], A_t, s_t, h[k], k % O))
    owner, A_all, b_all, h_all, which = (np.concatenate(c) for c in zip(*rows, strict=True))
    order = np.argsort(owner, kind="stable")  # by agent, each agent's rows in obstacle order
    offsets = np.zeros(M + 1, dtype=np.int64)
    np.add.at(offsets, owner + 1, 1)
    min_h = np.full(M, np.inf)
    np.minimum.at(min_h, agent, np.where(np.isfinite(h), h, -np.inf))
    return (
        np.cumsum(offsets),
        np.ascontiguousarray(A_all[order]),
        b_all[order],
        h_all[order],
        which[order].astype(np.int64),
        min_h,
    )
