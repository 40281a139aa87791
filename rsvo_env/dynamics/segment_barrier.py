"""The stopping-segment barrier of the double integrator (``docs/double_integrator.md``, "The
stopping-segment barrier", the default): each agent's backup (braking along its velocity) sweeps
the segment ``S_i = [p_i, q_i]``, ``q_i = p_i + v_i L_i / s_i``, ``L_i`` the stopping reach of
``backup_barrier`` (eq. ``reach``); under the backup the next segment lies inside this one. The
barrier is ``h_ij = dist(S_i, S_j) - r_i - r_j`` (``h_io = dist(S_i, segment_o) - r_i - rho_o``
for an obstacle), so agents are charged the segment they will sweep, not a disk: touching agents
at rest can part, agents side by side keep their speed.

With ``n`` the unit direction between the closest points (eq. ``separation``), ``h`` equals
``min_{S_i} n.x - max_{S_j} n.y - D`` now, and that bound at the next sample is separable:
agent i keeps its part if (eq. ``seg-rows``)

* row 1: ``n.p_i+ >= m_i - sigma``, with ``m_i = min_{S_i} n.x``, exact and linear;
* row 2: ``n.p_i+ + K_i n.w_i >= m_i - sigma`` (``w = v + dt a``,
  ``K_i = W_i / (2 c_i) + dt / 2``, ``W_i`` a bound on ``|w|`` over the trust box), which gives
  ``n.q_i+ >= m_i - sigma`` wherever ``n.w < 0``; where ``n.w >= 0`` the segment's near end is
  its lowest point and row 1 holds it.

``sigma`` is the R-SVO share of ``gamma dt h`` (eq. ``share`` of the backup barrier). The backup
meets row 1 with slack ``>= sigma`` and row 2 with slack
``sigma + |n.v_hat| (spare - kappa_i rho_i)`` where the segment's far end leads
(``n.v_hat < 0``; ``kappa_i = sqrt 2 dt |w_beta| / (2 c_i)``, eq. ``seg-remainder``), so each
agent's trust box ``|a - beta_i|_inf <= rho_i`` is the largest that keeps those >= 0.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from rsvo_env.dynamics.backup_barrier import (
    TRUST_SHRINK,
    AgentBoxes,
    AgentTerms,
    _store,
    _support,
    _trust_rows,
    agent_terms,
    settled,
)
from rsvo_env.dynamics.barriers import braking_capability
from rsvo_env.geometry.obstacles import nearest_points
from rsvo_env.geometry.segments import separation
from rsvo_env.qp.rows import Rows

_SQRT2 = np.sqrt(2.0)

__all__ = ["AgentBoxes", "segment_radii", "segment_rows"]


def kappa(t: AgentTerms, dt: float) -> NDArray[np.float64]:
    """Eq. ``seg-remainder``: row 2's loss at the backup per unit of trust radius and of
    ``|n.v_hat|``, ``sqrt 2 dt |v + dt beta| / (2 c)``."""
    w = np.where(t.speed >= t.c * dt, t.speed - t.c * dt, 0.0)
    return _SQRT2 * dt * w / (2.0 * t.c)


def _slacks(t: AgentTerms, owner: NDArray, e: NDArray, sigma: NDArray, dt: float):
    """Per directed row: ``n.v_hat`` and the slacks at the backup before the trust box, row 1's
    ``sigma + (n.p+(beta) - m)`` and row 2's ``sigma + |n.v_hat| spare`` where the far end
    leads; every term a product of terms >= 0, none a difference (the backup moves the near end
    by ``travel`` along the segment and the far end back by ``spare``)."""
    nv = (e * t.unit[owner]).sum(axis=-1)
    travel, spare = t.travel[owner], t.spare[owner]
    s, c = t.speed[owner], t.c[owner]
    # L - travel in closed form: (s - c dt)^2 / (2 c) + s dt / 2 while braking (the backup's
    # next reach plus c dt^2 / 2), s^2 / (2 c) = spare when it stops within the step
    brakes = s >= c * dt
    behind = np.where(brakes, (s - c * dt) ** 2 / (2.0 * c) + 0.5 * s * dt, spare)
    tau1 = sigma + np.where(nv >= 0, nv * travel, -nv * behind)
    tau2 = sigma + np.where(nv >= 0, nv * travel, -nv * spare)
    return nv, tau1, tau2


def segment_rows(
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
    """Every agent's rows of the stopping-segment barrier (module docstring) against the pairs
    (I, J) (weights (P, 2)) and the obstacles ``capsules`` ((E, O, 5) or (1, O, 5), ``n`` agents
    an env), stored by agent: two rows per pair, two per obstacle, then the four rows of its
    trust box; as :func:`rsvo_env.dynamics.backup_barrier.backup_rows`. Returns the rows and each
    agent's smallest obstacle h (None without obstacles)."""
    radii, lo, hi = bodies.radii, bodies.lo, bodies.hi
    M = len(positions)
    t = agent_terms(velocities, lo, hi, dt)
    reach = t.unit * t.L[:, None]  # each segment, from its agent
    d = positions[I] - positions[J]
    zero = np.zeros_like(d)
    e, bound = separation(d, d + reach[I], zero, reach[J], d)
    h = bound - radii[I] - radii[J]
    rate = gamma if dt is None else gamma * dt
    hp = rate * settled(h, np.sqrt((d * d).sum(axis=-1)) + t.L[I] + t.L[J])
    w = np.where(hp >= 0.0, weights[:, 0], weights[:, 1])
    owner, normals, shares = [I, J], [e, -e], [w * hp, (1.0 - w) * hp]
    hs, others = [h, h], [J, I]
    obstacle_h = None
    if capsules is not None:
        O = capsules.shape[1]
        caps = np.broadcast_to(capsules, (M // n, O, 5)) if capsules.shape[0] == 1 else capsules
        near = nearest_points(positions.reshape(-1, n, 2), caps).reshape(M * O, 2)
        agent = np.repeat(np.arange(M), O)
        cap = caps[agent // n, np.arange(M * O) % O]
        # coordinates about the obstacle's point nearest the agent, to keep them small
        a0 = positions[agent] - near
        e_o, bound_o = separation(a0, a0 + reach[agent], cap[:, 0:2] - near, cap[:, 2:4] - near, a0)
        h_o = bound_o - radii[agent] - cap[:, 4]
        owner.append(agent)
        normals.append(e_o)
        shares.append(rate * settled(h_o, np.sqrt((a0 * a0).sum(axis=-1)) + t.L[agent]))
        hs.append(h_o)
        others.append(-1 - np.arange(M * O) % O)
        obstacle_h = np.full(M, np.inf)
        np.minimum.at(obstacle_h, agent, np.where(np.isfinite(h_o), h_o, -np.inf))
    own = np.concatenate(owner)
    e_all, sigma = np.concatenate(normals), np.concatenate(shares)
    h_all, others_all = np.concatenate(hs), np.concatenate(others)
    if dt is None:
        A, b = _continuous(t, own, e_all, sigma)
        box_lo, box_hi, rho = lo, hi, None
    else:
        A, b, rho = _sampled(t, own, e_all, sigma, M, dt)
        box_lo = np.minimum(np.maximum(lo, t.beta - rho[:, None]), t.beta)
        box_hi = np.maximum(np.minimum(hi, t.beta + rho[:, None]), t.beta)
        own, h_all, others_all = (np.concatenate([x, x]) for x in (own, h_all, others_all))
    # bodies at one point (or a body on a wall's core) have no direction to part along: a row
    # no action meets flags the QP infeasible instead
    bad = ~(np.isfinite(A).all(axis=-1) & np.isfinite(b))
    if bad.any():
        A = np.where(bad[:, None], 0.0, A)
        b = np.where(bad, -1.0, b)
    keep = (not cull) | bad | (b < _support(A, box_lo[own], box_hi[own]))
    parts = [(own[keep], A[keep], b[keep], others_all[keep], h_all[keep])]
    if dt is not None:
        parts.append(_trust_rows(t.beta, rho, lo, hi, own, h_all, M, cull))
    owner_k, A_k, b_k, other_k, h_k = (np.concatenate(c) for c in zip(*parts, strict=True))
    rows = _store(M, owner_k, A_k, b_k, other_k, h_k)
    n_culled = len(b) + (4 * M if dt is not None else 0) - len(b_k)
    return Rows(**rows, pair_h=h, n_pairs=len(I), n_culled=n_culled), obstacle_h


def _sampled(t: AgentTerms, own: NDArray, e: NDArray, sigma: NDArray, M: int, dt: float):
    """Rows 1 and 2 (eq. ``seg-rows``) of every directed row, stacked, and each agent's trust
    radius: the largest (to ``rho_full``) with ``|n.v_hat| kappa rho <= tau2`` where the far end
    leads, shrunk by a relative hair so the backup keeps room for rounding."""
    nv, tau1, tau2 = _slacks(t, own, e, sigma, dt)
    k = kappa(t, dt)[own]
    lead = (nv < 0) & (k > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        limit = np.where(lead, np.maximum(tau2, 0.0) / (-nv * k), np.inf)
    rho_row = np.full(M, np.inf)
    np.minimum.at(rho_row, own, np.where(np.isnan(limit), 0.0, limit))
    rho = np.minimum(t.rho_full, rho_row * TRUST_SHRINK)
    w_beta = np.where(t.speed >= t.c * dt, t.speed - t.c * dt, 0.0)
    K = ((w_beta + _SQRT2 * dt * rho) / (2.0 * t.c) + 0.5 * dt)[own]
    A1 = -(0.5 * dt * dt) * e
    A2 = -(0.5 * dt * dt + dt * K)[:, None] * e
    # row 2 at the backup: n.w_beta = nv |w_beta|, and W - |w_beta| = sqrt 2 dt rho
    tau2 = np.where(nv >= 0, tau2 + K * nv * w_beta[own], tau2 + nv * k * rho[own])
    beta = t.beta[own]
    b1 = (A1 * beta).sum(axis=-1) + tau1
    b2 = (A2 * beta).sum(axis=-1) + tau2
    return np.concatenate([A1, A2]), np.concatenate([b1, b2]), rho


def _continuous(t: AgentTerms, own: NDArray, e: NDArray, sigma: NDArray):
    """``dt`` None: the rate of the segment's lowest end along n, one row per directed row: the
    far end's ``n.q' = n.v + (n s + (n.v) v_hat) . a / (2 c) >= -sigma`` where it leads
    (``n.v < 0``), else the near end's ``n.v >= -sigma`` (no input in it: a row ``0 . a <= b``)."""
    nv = (e * t.unit[own]).sum(axis=-1)
    s = t.speed[own]
    lead = (nv < 0)[:, None]
    rate = s[:, None] * (e + nv[:, None] * t.unit[own]) / (2.0 * t.c[own, None])
    A = np.where(lead, -rate, 0.0)
    return A, sigma + s * nv


def segment_radii(
    omega_floor: NDArray,
    velocities: NDArray,
    gamma: float,
    dt: float | None,
    radii: NDArray,
    lo: NDArray,
    hi: NDArray,
    speed_max: NDArray,
) -> NDArray[np.float64]:
    """Per agent and weight floor (E, N, K), the distance beyond which none of its segment rows
    with a positive weight can bind nor narrow its trust box (``docs/double_integrator.md``).

    ``dist(S_i, S_j) >= |d| - L_i - L_j``; a row cannot bind over the box nor set the trust
    radius once its share covers ``S_i = 2 kappa_i rho_full + 2 |U_i| |A_2|`` with
    ``rho_full <= 2 m_i``, ``|A_2| <= dt^2 + dt (s_i + 2 sqrt 2 dt m_i) / (2 c_i)``; in continuous
    time ``S_i = s_i (1 + |U_i| / c_i)``, as the backup barrier's."""
    c = braking_capability(lo, hi)
    speed = np.sqrt((velocities * velocities).sum(axis=-1))
    L = speed * speed / (2.0 * c) + (0.0 if dt is None else 0.5 * dt * speed)
    if dt is None:
        S, rate = speed * (1.0 + speed_max / c), gamma
    else:
        m = np.maximum(np.abs(lo), np.abs(hi)).max(axis=-1)
        A2 = dt * dt + dt * (speed + 2.0 * _SQRT2 * dt * m) / (2.0 * c)
        S = 2.0 * _SQRT2 * dt * speed * 2.0 * m / (2.0 * c) + 2.0 * speed_max * A2
        rate = gamma * dt
    base = radii + radii.max(axis=-1, keepdims=True) + L + L.max(axis=-1, keepdims=True)
    ok = np.isfinite(omega_floor)
    w = np.where(ok & (omega_floor > 0), omega_floor, 1.0)
    r = base[..., None] + S[..., None] / (w * rate)
    r = np.where(omega_floor > 0, r * (1.0 + 1e-9), np.inf)
    return np.where(ok, r, 0.0)
