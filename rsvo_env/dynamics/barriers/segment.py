"""The stopping-segment barrier of the double integrator (``docs/double_integrator.md``, "The
stopping-segment barrier", the default): each agent's backup (braking along its velocity) sweeps
the segment ``S_i = [p_i, q_i]``, ``q_i = p_i + v_i L_i / s_i``, ``L_i`` the stopping reach of
``stopping`` (eq. ``reach``); under the backup the next segment lies inside this one. The
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
from numba import njit
from numpy.typing import NDArray

from rsvo_env.dynamics.barriers.box import braking_capability
from rsvo_env.dynamics.barriers.stopping import (
    SETTLE,
    TRUST_SHRINK,
    AgentBoxes,
    AgentTerms,
    StoppingBarrier,
    agent_terms,
    binding,
    kept_rows,
    obstacle_slots,
    radius_beyond,
    row_kept,
    settled,
    stopping_reach,
    trust_box_rows,
)
from rsvo_env.geometry.segments import separate, separation
from rsvo_env.qp.rows import Rows
from rsvo_env.util.planar import norm

_SQRT2 = np.sqrt(2.0)
# the relative rounding of a coordinate after the few operations a bound takes
COORDINATES = 64.0 * np.finfo(np.float64).eps

__all__ = ["AgentBoxes", "segment_radii", "segment_rows"]


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
    trust box; as ``rsvo_env.dynamics.barriers.backup.backup_rows``. Returns the rows and each
    agent's smallest obstacle h (None without obstacles)."""
    radii, lo, hi = bodies.radii, bodies.lo, bodies.hi
    M = len(positions)
    t = agent_terms(velocities, lo, hi, dt)
    reach = t.unit * t.L[:, None]  # each segment, from its agent
    rate = gamma if dt is None else gamma * dt
    P = len(I)
    e, sigma_p, h = np.empty((2 * P, 2)), np.empty(2 * P), np.empty(P)
    _pair_terms(
        np.ascontiguousarray(positions),
        I,
        J,
        reach,
        t.L,
        radii,
        np.ascontiguousarray(weights),
        rate,
        SETTLE,
        e,
        sigma_p,
        h,
    )
    owner, normals, shares = [I, J], [e], [sigma_p]
    hs, others = [h, h], [J, I]
    obstacle_h = None
    if capsules is not None:
        agent, cap, near, neighbour = obstacle_slots(positions, capsules, n)
        # coordinates about the obstacle's point nearest the agent, to keep them small
        a0 = positions[agent] - near
        e_o, bound_o = separation(a0, a0 + reach[agent], cap[:, 0:2] - near, cap[:, 2:4] - near, a0)
        h_o = bound_o - radii[agent] - cap[:, 4]
        owner.append(agent)
        normals.append(e_o)
        # h_o carries the rounding of coordinates as large as the obstacle's ends and where it
        # lies, not only of the agent's distance and reach (a wall 2e7 m long: ~1e-9 m)
        far = np.maximum(norm(cap[:, 0:2] - near), norm(cap[:, 2:4] - near)) + norm(near)
        size = norm(a0) + t.L[agent] + (COORDINATES / SETTLE) * far
        shares.append(rate * settled(h_o, size))
        hs.append(h_o)
        others.append(neighbour)
        obstacle_h = np.full(M, np.inf)
        np.minimum.at(obstacle_h, agent, np.where(np.isfinite(h_o), h_o, -np.inf))
    own = np.concatenate(owner)
    e_all, sigma = np.concatenate(normals), np.concatenate(shares)
    h_all, others_all = np.concatenate(hs), np.concatenate(others)
    if dt is None:
        A, b = _continuous(t, own, e_all, sigma)
        keep = binding(A, b, own, lo, hi, cull)
        return kept_rows(M, (own, A, b, others_all, h_all), keep, None, h, len(I)), obstacle_h
    terms = (t.unit, t.travel, t.spare, t.speed, t.c, np.ascontiguousarray(t.beta), t.rho_full)
    rho, h_min, *kept = _sampled_rows(
        own,
        np.ascontiguousarray(e_all),
        sigma,
        h_all,
        others_all,
        *terms,
        np.ascontiguousarray(lo),
        np.ascontiguousarray(hi),
        dt,
        TRUST_SHRINK,
        cull,
    )
    trust = trust_box_rows(t.beta, rho, lo, hi, h_min, M, cull)
    return kept_rows(M, tuple(kept), None, trust, h, len(I), 2 * len(own)), obstacle_h


@njit(cache=True, error_model="numpy")
def _pair_terms(positions, I, J, reach, L, radii, weights, rate, settle, e, sigma, h):
    """Per pair k: the separating direction of the two stopping segments (eq. ``separation``)
    into ``e[k]`` (agent I's) and ``e[P + k] = -e[k]`` (agent J's), h (eq. ``seg-h``) into
    ``h[k]``, the R-SVO shares of ``rate h`` (eq. ``share``: a rounding below 0 read as 0,
    sign-aware below it) into ``sigma[k]`` and ``sigma[P + k]``. Coordinates about agent J,
    to keep them small."""
    P = len(I)
    for k in range(P):
        i, j = I[k], J[k]
        dx, dy = positions[i, 0] - positions[j, 0], positions[i, 1] - positions[j, 1]
        nx, ny, bound = separate(
            dx, dy, dx + reach[i, 0], dy + reach[i, 1], 0.0, 0.0, reach[j, 0], reach[j, 1], dx, dy
        )
        hk = bound - radii[i] - radii[j]
        size = np.sqrt(dx * dx + dy * dy) + L[i] + L[j]
        hp = rate * (hk if hk < -settle * size else max(hk, 0.0))
        w = weights[k, 0] if hp >= 0.0 else weights[k, 1]
        h[k] = hk
        e[k, 0], e[k, 1], e[P + k, 0], e[P + k, 1] = nx, ny, -nx, -ny
        sigma[k], sigma[P + k] = w * hp, (1.0 - w) * hp


@njit(cache=True, error_model="numpy")
def _sampled_rows(
    own, e, sigma, h, other, unit, travel, spare, speed, c, beta, rho_full, lo, hi, dt, shrink, cull
):
    """Rows 1 and 2 (eq. ``seg-rows``) of every directed row k (agent ``own[k]``, direction
    ``e[k]``, share ``sigma[k]``), those that can bind over the agent's trust box kept (all of
    them without ``cull``; an undefined row, of a body at another's centre, becomes
    ``0 . a <= -1`` and is kept, so the QP says infeasible: ``stopping.row_kept``).
    Returns each agent's trust radius, its smallest h, and the kept rows as (owner, A, b,
    neighbour, h): every kept row 1 in k order, then every kept row 2.

    The trust radius is the largest (to ``rho_full``) with ``|n.v_hat| kappa rho <= tau2``
    where the far end leads (eq. ``seg-remainder``, ``kappa = sqrt 2 dt |w_beta| / (2 c)``),
    shrunk by a relative hair so the backup keeps room for rounding. The slacks of rows 1 and
    2 at the backup before the trust box are sums of products of terms >= 0, none a
    difference: the backup moves the near end by ``travel`` along the segment and the far end
    back by ``spare``; ``L - travel`` (``behind``) is ``(s - c dt)^2 / (2 c) + s dt / 2`` while
    braking, ``spare`` when it stops within the step. Both sides of ``n.v_hat >= 0`` are
    computed and one selected: the sign is a coin toss from row to row, and a branch on it
    costs more than the sums."""
    K, M = len(own), len(rho_full)
    w_beta, kap, behind = np.empty(M), np.empty(M), np.empty(M)
    K2, a2, rho, h_min = np.empty(M), np.empty(M), np.empty(M), np.full(M, np.inf)
    box = np.empty((M, 4))
    for i in range(M):
        s, ci = speed[i], c[i]
        braking = s >= ci * dt
        w_beta[i] = s - ci * dt if braking else 0.0
        kap[i] = np.sqrt(2.0) * dt * w_beta[i] / (2.0 * ci)
        behind[i] = (s - ci * dt) ** 2 / (2.0 * ci) + 0.5 * s * dt if braking else spare[i]
        rho[i] = np.inf
    for k in range(K):
        i = own[k]
        nv = e[k, 0] * unit[i, 0] + e[k, 1] * unit[i, 1]
        limit = max(sigma[k] - nv * spare[i], 0.0) / (-nv * kap[i])
        limit = 0.0 if np.isnan(limit) else limit
        rho[i] = min(rho[i], limit if (nv < 0 and kap[i] > 0) else np.inf)
        h_min[i] = np.minimum(h_min[i], h[k])
    a1 = 0.5 * dt * dt
    for i in range(M):
        rho[i] = min(rho_full[i], rho[i] * shrink)
        K2[i] = (w_beta[i] + np.sqrt(2.0) * dt * rho[i]) / (2.0 * c[i]) + 0.5 * dt
        a2[i] = a1 + dt * K2[i]
        for d in range(2):  # the trust box within the agent's own, about beta
            b_lo = np.minimum(np.maximum(lo[i, d], beta[i, d] - rho[i]), beta[i, d])
            b_hi = np.maximum(np.minimum(hi[i, d], beta[i, d] + rho[i]), beta[i, d])
            box[i, 2 * d], box[i, 2 * d + 1] = b_lo, b_hi
    owner_k, other_k = np.empty(2 * K, dtype=np.int64), np.empty(2 * K, dtype=np.int64)
    A_k, b_k, h_k = np.empty((2 * K, 2)), np.empty(2 * K), np.empty(2 * K)
    n1 = 0
    n2 = K  # the kept rows 2 from K on, moved behind the rows 1 at the end
    for k in range(K):
        i = own[k]
        nv = e[k, 0] * unit[i, 0] + e[k, 1] * unit[i, 1]
        lead = nv < 0
        ahead = sigma[k] + nv * travel[i]
        # row 2 at the backup: n.w_beta = nv |w_beta|, and W - |w_beta| = sqrt 2 dt rho
        tau1 = sigma[k] - nv * behind[i] if lead else ahead
        tau2 = (
            (sigma[k] - nv * spare[i]) + nv * kap[i] * rho[i]
            if lead
            else (ahead + K2[i] * nv * w_beta[i])
        )
        for row in range(2):
            a = a1 if row == 0 else a2[i]
            Ax, Ay = -a * e[k, 0], -a * e[k, 1]
            bk = Ax * beta[i, 0] + Ay * beta[i, 1] + (tau1 if row == 0 else tau2)
            Ax, Ay, bk, keep = row_kept(
                Ax, Ay, bk, box[i, 0], box[i, 1], box[i, 2], box[i, 3], cull
            )
            if keep:
                q = n1 if row == 0 else n2
                owner_k[q], other_k[q], h_k[q] = i, other[k], h[k]
                A_k[q, 0], A_k[q, 1], b_k[q] = Ax, Ay, bk
                if row == 0:
                    n1 += 1
                else:
                    n2 += 1
    m = n2 - K
    owner_k[n1 : n1 + m], other_k[n1 : n1 + m] = owner_k[K:n2], other_k[K:n2]
    A_k[n1 : n1 + m], b_k[n1 : n1 + m], h_k[n1 : n1 + m] = A_k[K:n2], b_k[K:n2], h_k[K:n2]
    c1 = n1 + m
    return rho, h_min, owner_k[:c1], A_k[:c1], b_k[:c1], other_k[:c1], h_k[:c1]


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
    radius once its share covers ``S_i = kappa_i rho_full + 2 |U_i| |A_2|`` (row 2's slack is
    at least ``sigma - kappa_i rho_full``) with
    ``rho_full <= 2 m_i``, ``|A_2| <= dt^2 + dt (s_i + 2 sqrt 2 dt m_i) / (2 c_i)``; in continuous
    time ``S_i = s_i (1 + |U_i| / c_i)``, as the backup barrier's."""
    c = braking_capability(lo, hi)
    speed = np.sqrt((velocities * velocities).sum(axis=-1))
    if dt is None:
        S, rate = speed * (1.0 + speed_max / c), gamma
    else:
        m = np.maximum(np.abs(lo), np.abs(hi)).max(axis=-1)
        A2 = dt * dt + dt * (speed + 2.0 * _SQRT2 * dt * m) / (2.0 * c)
        S = _SQRT2 * dt * speed * 2.0 * m / (2.0 * c) + 2.0 * speed_max * A2
        rate = gamma * dt
    return radius_beyond(omega_floor, radii, stopping_reach(speed, c, dt), S, rate)


class Segment(StoppingBarrier):
    """The stopping-segment barrier (module docstring)."""

    name = "segment"
    rows = staticmethod(segment_rows)
    radii = staticmethod(segment_radii)
