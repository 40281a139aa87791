"""What the backup and stopping-segment barriers share (``docs/double_integrator.md``, "The
backup barrier"): each agent's stopping reach and backup action (braking along its velocity), its
trust box, the culling of rows that cannot bind over it, the rows' storage by agent, and the
culling radius of a barrier whose h is bounded by the stopping reaches.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env.dynamics.barriers.box import box_support, braking_capability
from rsvo_env.dynamics.barriers.interface import Barrier
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
    """``AgentTerms`` of agents with velocities ``v`` (M, 2) and boxes (M, 2)."""
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


class AgentBoxes(NamedTuple):
    """Each agent's body radius (M,) and input box ``lo``, ``hi`` (M, 2)."""

    radii: NDArray
    lo: NDArray
    hi: NDArray


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
    """One row ``(ax, ay) . a <= b`` as ``binding`` keeps it: ``(ax, ay, b, keep)``, an
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


class StoppingBarrier(Barrier):
    """A barrier charged with the stopping reach of every agent's backup (the backup and the
    stopping-segment barriers): the backup meets all of an agent's rows at once while every
    ``h >= 0``; ``rows`` and ``radii`` are its module's row and culling functions."""

    backed = True

    @staticmethod
    def rows(*args, **kwargs) -> tuple[Rows, NDArray | None]:
        raise NotImplementedError

    @staticmethod
    def radii(*args) -> NDArray[np.float64]:
        raise NotImplementedError

    def filter_rows(self, cfg, positions, velocities, weights, I, J, bodies, capsules, n):
        return self.rows(positions, velocities, weights, I, J, cfg.gamma, cfg.dt, bodies,
                         capsules, n)  # fmt: skip

    def culling_radii(self, cfg, omega_floor, velocities, bodies):
        E, n = velocities.shape[:2]
        return self.radii(
            omega_floor,
            velocities,
            cfg.gamma,
            cfg.dt,
            bodies.radii.reshape(E, n),
            bodies.lo.reshape(E, n, 2),
            bodies.hi.reshape(E, n, 2),
            bodies.speed.reshape(E, n),
        )
