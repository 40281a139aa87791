"""The backup barrier of the double integrator (``docs/double_integrator.md``, "The backup
barrier"): each agent braking along its own velocity is one action that meets every one of its
rows at once, against any number of neighbours and obstacles, so every QP is feasible while
every ``h >= 0``; exact in sampled time (zero-order hold) for any accepted ``gamma dt``.

Per agent i, with speed ``s_i = |v_i|`` and ``c_i`` the deceleration its box guarantees in every
direction (``barriers.braking_capability``):

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

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env.dynamics.barriers import box_support, braking_capability
from rsvo_env.geometry.obstacles import nearest_points
from rsvo_env.qp.rows import Rows

# the trust box is solved for a remainder a relative hair below the smallest slack, so the
# backup meets the tightest row with room for rounding
TRUST_SHRINK = 1.0 - 1e-9
# h below 0 by less than this share of its terms is rounding, read as 0: the hair the collision
# test (a distance below (r_i + r_j)(1 - 1e-9)) and the solver's feasibility allowance leave too
SETTLE = 1e-9
_SQRT_HALF = np.sqrt(0.5)


def settled(h: NDArray, size: NDArray) -> NDArray[np.float64]:
    """``h`` with a negative value within rounding of 0 (``SETTLE`` of the terms it is made of,
    ``size``: the distance and the reaches, as each caller passes them) read as 0. A pair resting at
    h = 0 drifts by roundings around it (the state's, and the solver's allowance of ``1e-12`` of a
    row's terms a step); reading those as violations would ask a resting agent for a recovery it
    cannot make. A state truly below 0 keeps its h, so the rows ask it to recover at the rate gamma
    dt."""
    return np.where(h < -SETTLE * size, h, np.maximum(h, 0.0))


def stopping_reach(speed: NDArray, c: NDArray, dt: float | None) -> NDArray[np.float64]:
    """Eq. ``reach``: ``s^2 / (2 c) + s dt / 2`` (``s^2 / (2 c)`` in continuous time)."""
    L = speed * speed / (2.0 * c)
    return L if dt is None else L + 0.5 * dt * speed


def backup_action(v: NDArray, c: NDArray, dt: float | None) -> NDArray[np.float64]:
    """Eq. ``backup``: braking at ``c`` along the velocity, or the action that stops within
    the step when braking at ``c`` would reverse it (``dt`` None: braking at ``c``; 0 at rest)."""
    s = np.sqrt((v * v).sum(axis=-1))
    with np.errstate(divide="ignore", invalid="ignore"):
        brake = np.where(s[..., None] > 0, -c[..., None] * v / s[..., None], 0.0)
    if dt is None:
        return brake
    return np.where((s >= c * dt)[..., None], brake, -v / dt)


def remainder(rho: NDArray, c: NDArray, dt: float) -> NDArray[np.float64]:
    """Eq. ``remainder``: a bound on how far the stopping reach after the step lies above its
    tangent at the backup, over the trust box of radius ``rho``."""
    return dt * dt * (rho * rho / c + _SQRT_HALF * rho)


def trust_radius(tau: NDArray, c: NDArray, dt: float) -> NDArray[np.float64]:
    """The root ``rho >= 0`` of ``remainder(rho) = tau`` (``tau >= 0``), in a form without
    cancellation."""
    x = tau / (dt * dt)
    return 2.0 * x / (_SQRT_HALF + np.sqrt(0.5 + 4.0 * x / c))


@dataclass(frozen=True)
class AgentTerms:
    """What each agent's rows share (M agents): deceleration ``c``, speed, reach ``L``, the
    backup ``beta``, the gradient ``g`` of the reach after the step, the unit velocity ``unit``
    (0 at rest), the backup's travel ``|dp(beta)|`` and its ``spare`` ``L - L(|v + dt beta|) -
    travel`` (Lemma 1: ``c dt^2 / 2`` while ``s >= c dt``, else ``s^2 / (2 c)``), and the box
    radius ``rho_full`` around the backup that covers the whole box."""

    c: NDArray
    speed: NDArray
    L: NDArray
    beta: NDArray
    g: NDArray
    unit: NDArray
    travel: NDArray
    spare: NDArray
    rho_full: NDArray


def agent_terms(v: NDArray, lo: NDArray, hi: NDArray, dt: float | None) -> AgentTerms:
    """:class:`AgentTerms` of agents with velocities ``v`` (M, 2) and boxes (M, 2)."""
    c = braking_capability(lo, hi)
    speed = np.sqrt((v * v).sum(axis=-1))
    L = stopping_reach(speed, c, dt)
    beta = backup_action(v, c, dt)
    rho_full = np.maximum(hi - beta, beta - lo).max(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        unit = np.where(speed[:, None] > 0, v / speed[:, None], 0.0)
    if dt is None:  # continuous time: the rows' gradient is v / c, no step, no trust box
        zero = 0.0 * L
        return AgentTerms(c, speed, L, beta, v / c[:, None], unit, zero, zero, rho_full)
    w = v + dt * beta
    # Lemma 1's terms in closed form: the slack at the backup is their sum, each >= 0, so it
    # keeps the c dt^2 / 2 it exceeds 0 by at any speed (a difference of reaches would lose it
    # to a rounding of s^2 / c)
    brakes = speed >= c * dt
    travel = np.where(brakes, speed * dt - 0.5 * c * dt * dt, 0.5 * speed * dt)
    spare = np.where(brakes, 0.5 * c * dt * dt, speed * speed / (2.0 * c))
    return AgentTerms(c, speed, L, beta, dt * w / c[:, None], unit, travel, spare, rho_full)


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


class AgentBoxes(NamedTuple):
    """Each agent's body radius (M,) and input box ``lo``, ``hi`` (M, 2)."""

    radii: NDArray
    lo: NDArray
    hi: NDArray


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
    ``hi`` (M, 2) (:class:`AgentBoxes`, or the filter's ``Bodies``). Returns the rows and each
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


def binding(
    A: NDArray, b: NDArray, owner: NDArray, box_lo: NDArray, box_hi: NDArray, cull: bool
) -> NDArray[np.bool_]:
    """Which rows to keep: those that can bind over their agent's trust box ``[box_lo,
    box_hi]`` (every row without ``cull``; the trust rows keep the solution inside the box).
    A body at another's centre (or on a wall's core) has no direction to keep away along: its
    undefined row becomes ``0 . a <= -1`` (in place), which no action meets, and is kept, so
    the QP says infeasible."""
    keep = np.empty(len(b), dtype=np.bool_)
    _binding(A, b, owner, np.ascontiguousarray(box_lo), np.ascontiguousarray(box_hi), cull, keep)
    return keep


@njit(cache=True, error_model="numpy")
def _binding(A, b, owner, box_lo, box_hi, cull, keep):
    for k in range(len(b)):
        i = owner[k]
        A[k, 0], A[k, 1], b[k], keep[k] = row_kept(
            A[k, 0], A[k, 1], b[k], box_lo[i, 0], box_hi[i, 0], box_lo[i, 1], box_hi[i, 1], cull
        )


@njit(cache=True, inline="always", error_model="numpy")
def row_kept(ax, ay, b, lo_x, hi_x, lo_y, hi_y, cull):
    """One row ``(ax, ay) . a <= b`` as :func:`binding` keeps it: ``(ax, ay, b, keep)``, an
    undefined row made ``0 . a <= -1`` and kept, a defined one kept where it can bind over
    the box ``[lo, hi]`` (or always without ``cull``)."""
    if not (np.isfinite(ax) and np.isfinite(ay) and np.isfinite(b)):
        return 0.0, 0.0, -1.0, True
    top = max(ax * lo_x, ax * hi_x) + max(ay * lo_y, ay * hi_y)
    return ax, ay, b, (not cull) or b < top


def obstacle_slots(positions: NDArray, capsules: NDArray, n: int):
    """Every (agent, obstacle) slot of a batch of ``n`` agents an env, agent-major: the agent
    (M O,), its capsule (M O, 5), the capsule's point nearest the agent (M O, 2) and the
    obstacle as a row's neighbour, ``-1 - o``."""
    M, O = len(positions), capsules.shape[1]
    caps = np.broadcast_to(capsules, (M // n, O, 5)) if capsules.shape[0] == 1 else capsules
    near = nearest_points(positions.reshape(-1, n, 2), caps).reshape(M * O, 2)
    agent = np.repeat(np.arange(M), O)
    slot = np.arange(M * O) % O
    return agent, caps[agent // n, slot], near, -1 - slot


def kept_rows(
    M: int,
    rows: tuple,
    keep: NDArray | None,
    trust: tuple | None,
    pair_h: NDArray,
    n_pairs: int,
    examined: int | None = None,
) -> Rows:
    """The barrier's rows (owner, A, b, neighbour, h) where ``keep`` (None: ``rows`` are the
    kept ones, of ``examined``), then each agent's trust rows (``trust_box_rows``, None in
    continuous time), stored by agent."""
    parts = [rows if keep is None else tuple(x[keep] for x in rows)]
    if trust is not None:
        parts.append(trust)
    owner_k, A_k, b_k, other_k, h_k = (np.concatenate(c) for c in zip(*parts, strict=True))
    stored = _store(M, owner_k, A_k, b_k, other_k, h_k)
    if keep is not None:
        examined = len(keep)
    assert examined is not None  # given with the kept rows (keep None)
    n_culled = examined + (4 * M if trust is not None else 0) - len(b_k)
    return Rows(**stored, pair_h=pair_h, n_pairs=n_pairs, n_culled=n_culled)


def smallest_by_owner(owner: NDArray, h: NDArray, M: int) -> NDArray[np.float64]:
    """(M,) each agent's smallest h over its rows (inf without one)."""
    h_min = np.full(M, np.inf)
    np.minimum.at(h_min, owner, h)
    return h_min


def trust_box_rows(beta, rho, lo, hi, h_min, M, cull):
    """Each agent's trust box ``|a - beta|_inf <= rho`` as four rows (the QP keeps the agent's
    own box, so its round-off allowances stay in the box's units), the agent itself as their
    neighbour, its smallest h (``h_min``) as their h; those the box makes redundant culled."""
    A = np.tile(np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]]), (M, 1))
    sign = A.sum(axis=-1)
    agent = np.repeat(np.arange(M), 4)
    b = sign * beta[agent, np.tile([0, 0, 1, 1], M)] + rho[agent]
    keep = (not cull) | (b < box_support(A, lo[agent], hi[agent]))
    return agent[keep], A[keep], b[keep], agent[keep], h_min[agent[keep]]


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


def _store(M, owner, A, b, other, h) -> dict:
    """Rows stored by agent (stable: each agent's pair rows in pair order, then its obstacle
    rows, then its trust rows)."""
    order = np.argsort(owner, kind="stable")
    offsets = np.zeros(M + 1, dtype=np.int64)
    offsets[1:] = np.cumsum(np.bincount(owner, minlength=M))
    R = len(order)
    return {
        "flat_A": np.ascontiguousarray(A[order]),
        "flat_b": np.ascontiguousarray(b[order]),
        "offsets": offsets,
        "flat_neighbor": other[order].astype(np.int64),
        "flat_h": h[order],
        "flat_unrecoverable": np.zeros(R, dtype=bool),
        "flat_capped": np.zeros(R, dtype=bool),
    }


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


def radius_beyond(
    omega_floor: NDArray, radii: NDArray, L: NDArray, S: NDArray, rate: float
) -> NDArray[np.float64]:
    """The culling radius of a barrier whose h is at least ``|d| - (r_i + r_max) - L_i -
    L_max`` and whose rows of agent i cannot bind once their share ``omega rate h`` covers
    ``S_i``: ``r_i + r_max + L_i + L_max + S_i / (omega_floor rate)`` per weight floor
    (E, N, K); 0 for a floor that is not finite, infinite for a floor of 0."""
    base = radii + radii.max(axis=-1, keepdims=True) + L + L.max(axis=-1, keepdims=True)
    ok = np.isfinite(omega_floor)
    w = np.where(ok & (omega_floor > 0), omega_floor, 1.0)
    r = base[..., None] + S[..., None] / (w * rate)
    # the bound is exact only in exact arithmetic: a pair right at it stays examined
    r = np.where(omega_floor > 0, r * (1.0 + 1e-9), np.inf)
    return np.where(ok, r, 0.0)
