"""The backup barrier of the double integrator (``docs/double_integrator.md``, "The backup
barrier"): each agent braking along its own velocity is one action that meets every one of its
rows at once, against any number of neighbours and obstacles, so every QP is feasible while
every ``h >= 0``; exact in sampled time (zero-order hold) for any accepted ``gamma dt``.

Per agent i, with speed ``s_i = |v_i|`` and ``c_i`` the deceleration its box guarantees in every
direction (``box.braking_capability``):

* stopping reach (eq. ``reach``): ``L_i = s_i^2 / (2 c_i) + s_i dt / 2`` (``dt`` None:
  ``s_i^2 / (2 c_i)``), the distance the backup still travels;
* backup action (eq. ``backup``): ``beta_i = -c_i v_i / s_i`` while ``s_i >= c_i dt``, else
  ``-v_i / dt`` (it stops within the step instead of reversing);
* barrier (eq. ``h``): ``h_ij = |p_i - p_j| - (r_i + r_j) - L_i - L_j`` for a pair,
  ``h_io = dist(p_i, segment_o) - r_i - rho_o - L_i`` for an obstacle (weight 1).

Agent i's row against a neighbour or obstacle, unit normal ``e`` pointing to i, share
``sigma = omega_ij gamma dt h`` (eq. ``share``; a rounding below 0 read as 0, ``omega_ji``
for ``omega_ij`` where h < 0), is
``A . a <= b`` with ``A = g_i - (dt^2 / 2) e``, ``g_i = dt (v_i + dt beta_i) / c_i``, and
``b = A . beta_i + tau - R_i`` (eq. ``row``), where
``tau = sigma + e . dp_i(beta_i) + L_i - L(|v_i + dt beta_i|)`` is the row's slack at the backup
and ``R_i = dt^2 (rho_i^2 / c_i + rho_i / sqrt 2)`` (eq. ``remainder``) bounds the curvature of
the stopping reach over the agent's trust box ``|a - beta_i|_inf <= rho_i``, the largest with
``R_i <= min tau`` over its rows; four more rows keep the action in the trust box.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from rsvo_env.dynamics.barriers.box import braking_capability
from rsvo_env.dynamics.barriers.stopping import (
    TRUST_SHRINK,
    AgentBoxes,
    AgentTerms,
    StoppingBarrier,
    agent_terms,
    binding,
    kept_rows,
    obstacle_slots,
    radius_beyond,
    remainder,
    settled,
    smallest_by_owner,
    stopping_reach,
    trust_box_rows,
    trust_radius,
)
from rsvo_env.qp.rows import Rows


def _directed(t: AgentTerms, owner: NDArray, e: NDArray, sigma: NDArray, dt: float | None):
    """One directed row per (owner, normal e, share sigma): its A and its slack tau at the
    backup (sampled time), or A and b (continuous time). The backup moves along ``unit`` by
    ``travel``, so ``tau = sigma + (1 + e . unit) travel + spare``, with ``1 + e . unit`` as
    ``|e + unit|^2 / 2``: every term >= 0 and none a difference."""
    if dt is None:
        return t.g[owner], sigma + np.einsum("kd,kd->k", e, t.g[owner] * t.c[owner, None])
    A = t.g[owner] - (0.5 * dt * dt) * e
    u = t.unit[owner]
    toward = np.where(t.travel[owner] > 0, 0.5 * ((e + u) * (e + u)).sum(axis=-1), 0.0)
    return A, sigma + toward * t.travel[owner] + t.spare[owner]


def backup_rows(
    positions: NDArray,
    velocities: NDArray,
    weights: NDArray,
    I: NDArray,
    J: NDArray,
    gamma: float,
    dt: float | None,
    bodies: AgentBoxes,
    capsules: NDArray | None = None,
    n: int = 0,
    cull: bool = True,
) -> tuple[Rows, NDArray | None]:
    """Every agent's rows of the backup barrier (module docstring) against the pairs (I, J)
    (weights (P, 2)) and the obstacles ``capsules`` ((E, O, 5) or (1, O, 5), ``n`` agents an
    env), stored by agent: pair rows, obstacle rows, then the four rows of its trust box (the
    agent itself their neighbour). ``bodies``: each agent's body radius (M,) and box ``lo``,
    ``hi`` (M, 2) (``AgentBoxes``, or the filter's ``Bodies``). Returns the rows and each
    agent's smallest obstacle h (None without obstacles)."""
    radii, lo, hi = bodies.radii, bodies.lo, bodies.hi
    M = len(positions)
    t = agent_terms(velocities, lo, hi, dt)
    d = positions[I] - positions[J]
    dist = np.sqrt((d * d).sum(axis=-1))
    with np.errstate(divide="ignore", invalid="ignore"):
        e = d / dist[:, None]
    h = dist - radii[I] - radii[J] - t.L[I] - t.L[J]
    rate = gamma if dt is None else gamma * dt
    owner = [I, J]
    normals = [e, -e]
    hp = rate * settled(h, dist + t.L[I] + t.L[J])
    # while h >= 0 the egoist (larger omega) keeps the larger share of the slack; below 0 the
    # share is a deficit to make up, and the egoist takes the smaller one (the sign-aware split)
    w = np.where(hp >= 0.0, weights[:, 0], weights[:, 1])
    shares = [w * hp, (1.0 - w) * hp]
    hs, others = [h, h], [J, I]
    obstacle_h = None
    if capsules is not None:
        agent, cap, near, neighbour = obstacle_slots(positions, capsules, n)
        d_o = positions[agent] - near
        dist_o = np.sqrt((d_o * d_o).sum(axis=-1))
        with np.errstate(divide="ignore", invalid="ignore"):
            e_o = d_o / dist_o[:, None]
        h_o = dist_o - radii[agent] - cap[:, 4] - t.L[agent]
        owner.append(agent)
        normals.append(e_o)
        shares.append(rate * settled(h_o, dist_o + t.L[agent]))
        hs.append(h_o)
        others.append(neighbour)
        obstacle_h = np.full(M, np.inf)
        np.minimum.at(obstacle_h, agent, np.where(np.isfinite(h_o), h_o, -np.inf))
    owner_all = np.concatenate(owner)
    A, slack = _directed(t, owner_all, np.concatenate(normals), np.concatenate(shares), dt)
    h_all = np.concatenate(hs)
    others_all = np.concatenate(others)
    box_lo, box_hi = lo, hi
    if dt is not None:
        b, rho = _trust(t, owner_all, A, slack, M, dt)
        box_lo = np.minimum(np.maximum(lo, t.beta - rho[:, None]), t.beta)
        box_hi = np.maximum(np.minimum(hi, t.beta + rho[:, None]), t.beta)
    else:
        b = slack
    keep = binding(A, b, owner_all, box_lo, box_hi, cull)
    trust = None
    if dt is not None:
        trust = trust_box_rows(t.beta, rho, lo, hi, smallest_by_owner(owner_all, h_all, M), M, cull)
    rows = kept_rows(M, (owner_all, A, b, others_all, h_all), keep, trust, h, len(I))
    return rows, obstacle_h


def _trust(
    t: AgentTerms, owner: NDArray, A: NDArray, tau: NDArray, M: int, dt: float
) -> tuple[NDArray, NDArray]:
    """Each agent's trust radius from its smallest slack and the rows' right sides (eq.
    ``row``)."""
    tau_min = np.full(M, np.inf)
    np.minimum.at(tau_min, owner, np.where(np.isnan(tau), -np.inf, tau))
    R_full = remainder(t.rho_full, t.c, dt)
    full = tau_min >= R_full
    part = trust_radius(np.clip(tau_min, 0.0, R_full) * TRUST_SHRINK, t.c, dt)
    rho = np.where(full, t.rho_full, part)
    R = np.where(full, R_full, remainder(rho, t.c, dt))
    return np.einsum("kd,kd->k", A, t.beta[owner]) + tau - R[owner], rho


def backup_radii(
    omega_floor: NDArray,
    velocities: NDArray,
    gamma: float,
    dt: float | None,
    radii: NDArray,
    lo: NDArray,
    hi: NDArray,
    speed_max: NDArray,
) -> NDArray[np.float64]:
    """Per agent and weight floor (E, N, K), the distance beyond which none of its backup rows
    with a positive weight can bind nor narrow its trust box (``docs/double_integrator.md``).

    Agent i's row cannot bind over its box, nor set its trust radius, once its share
    ``omega gamma dt h`` (which bounds its slack ``tau`` from below) covers
    ``S_i = R_i(rho_full) + |A| max |a - beta| <= R_i(2 m_i) + 2 |U_i| (dt s_i / c_i + dt^2 / 2)``
    (``m_i`` the box's largest component, ``U_i`` its longest input); ``h >= |d| - (r_i +
    r_max) - L_i - L_max``. In continuous time ``S_i = s_i (1 + |U_i| / c_i)``.
    ``radii``, ``lo``, ``hi``, ``speed_max`` (the box's longest input) per agent, (E, N, ...).
    """
    c = braking_capability(lo, hi)
    speed = np.sqrt((velocities * velocities).sum(axis=-1))
    L = stopping_reach(speed, c, dt)
    if dt is None:
        S, rate = speed * (1.0 + speed_max / c), gamma
    else:
        m = np.maximum(np.abs(lo), np.abs(hi)).max(axis=-1)
        S = remainder(2.0 * m, c, dt) + 2.0 * speed_max * (dt * speed / c + 0.5 * dt * dt)
        rate = gamma * dt
    return radius_beyond(omega_floor, radii, L, S, rate)


class Backup(StoppingBarrier):
    """The backup (stopping-disk) barrier (module docstring)."""

    name = "backup"
    rows = staticmethod(backup_rows)
    radii = staticmethod(backup_radii)
