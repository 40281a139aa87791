"""The braking and HOCBF barriers' pair rows for the double integrator
(``docs/double_integrator.md``), vectorised over all pairs: one pair row
``c (-dp.a_i + dp.a_j) <= RHS`` split into ``-c dp.a_i <= s_ij`` and ``c dp.a_j <= s_ji`` with
``s_ij + s_ji = RHS``, each agent's row stored by agent (``rsvo_env.qp.rows.Rows``). A batch
of E envs is one flat set of E * N agents: agent ``e * N + i`` is agent i of env e, and pairs
never cross envs.
"""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from rsvo_env.dynamics.barriers.box import (
    box_support,
    braking_capability,
    largest_input,
    support_within,
)
from rsvo_env.dynamics.barriers.sampled import sampled_braking_rhs
from rsvo_env.qp.rows import PairFlags, Rows, finish
from rsvo_env.util.validation import shown

SPLITS = ("capability", "sign_aware", "paper")


def braking_rhs(
    dist: NDArray,
    dpdv: NDArray,
    dv2: NDArray,
    Ds: float | NDArray,
    A: float | NDArray,
    U: float | NDArray,
    gamma: float,
    dt: float | None,
    push: NDArray,
) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray]:
    """The braking barrier's row ``-dp.(a_i - a_j) <= RHS`` of pairs (or of an agent and a
    fixed circle, ``A = a_max``): closing speed q, h, RHS, which rows exist, and the pairs of
    the nearly head-on window (``docs/double_integrator.md``) that need the tangential row,
    ``push`` the most evasive push the boxes allow along dp. ``A``: the pair's braking
    capability ``a_i + a_j``; ``U``: half the largest relative acceleration,
    ``(|U_i| + |U_j|) / 2``; each a number or one per pair."""
    with np.errstate(divide="ignore", invalid="ignore"):
        q = dpdv / dist
        closing = q < 0.0
        h = dist - Ds - np.maximum(0.0, -q) ** 2 / (2.0 * A)
        rhs = (dv2 - q * q) - A * dist + gamma * h * A * dist / (-q)
    if dt is None:
        return q, h, np.where(closing, rhs, np.inf), closing, np.zeros(0, dtype=np.int64)
    # While opening (q >= 0) h = |dp| - Ds has relative degree 1 in continuous time, so it gets
    # no row there; a sampled system can still cross q = 0 and land at h < 0 within one step.
    # The one-step condition h+ >= (1 - gamma dt) h, with h+ from the exact second-order
    # expansion of |dp| under constant a, closes that gap.
    with np.errstate(invalid="ignore"):
        rhs_open = (dv2 - q * q) + 2.0 * dist * (q + gamma * (dist - Ds)) / dt
    rhs = np.where(closing, rhs, rhs_open)
    # and the sampled-data row: h at the next sample, not only its rate now
    args = (dist, q, dv2, h, A, U, gamma, dt, Ds)
    sampled = sampled_braking_rhs(*args)
    # Nearly head-on at h ~ 0 the reversal bound E can keep full braking out of the row: there E
    # is dropped and one more row forbids reversing the tangential speed within the step, which
    # full braking (no tangential part) meets.
    wt2 = np.maximum(dv2 - q * q, 0.0)
    stuck = (sampled < -push) & (h >= 0) & (wt2 > 0)
    if stuck.any():
        sampled = np.where(stuck, sampled_braking_rhs(*args, reversal=False), sampled)
    return q, h, np.minimum(rhs, sampled), np.ones(len(dist), dtype=bool), np.nonzero(stuck)[0]


def _tangential_rows(
    k: NDArray, dp: NDArray, dv: NDArray, dist: NDArray, q: NDArray, w: NDArray, dt: float
) -> tuple[NDArray, NDArray, NDArray]:
    """The tangential rows of pairs ``k``: ``-e_t.(a_i - a_j) <= w_t / dt``, scaled by ``|dp|``
    like the others, split by the pair's weights (a RHS >= 0 gives every split omega RHS).
    Returns agent i's row ``A_t`` (k, 2) and both shares."""
    wt = np.sqrt(np.maximum((dv[k] ** 2).sum(axis=1) - q[k] ** 2, 0.0))
    e_t = (dv[k] - q[k, None] * dp[k] / dist[k, None]) / wt[:, None]
    rhs_t = dist[k] * wt / dt
    return -dist[k, None] * e_t, w[k] * rhs_t, (1.0 - w[k]) * rhs_t


class BarrierSpec(NamedTuple):
    """A double-integrator pair barrier's settings: its gain ``gamma`` (Eq. (6); ``gamma2`` the
    HOCBF's second, None: ``gamma``), the safe distance ``safety_radius``, one box ``lo``,
    ``hi`` (2,) or one per agent (n, 2), the barrier, the split, and ``dt`` (None: continuous
    time)."""

    gamma: float
    safety_radius: float
    lo: NDArray
    hi: NDArray
    barrier: str = "braking"
    split: str = "capability"
    gamma2: float | None = None
    dt: float | None = None


def double_integrator_rows(
    positions: NDArray,
    velocities: NDArray,
    omega_pairs: NDArray,
    I: NDArray,
    J: NDArray,
    spec: BarrierSpec,
    cull: bool = True,
    radii: NDArray | None = None,
) -> Rows:
    """Rows for the double integrator (``docs/double_integrator.md``) under ``spec``
    (``BarrierSpec``).

    ``lo``, ``hi``: one box (2,) or one per agent (n, 2); ``radii`` (n,): body radii, a pair
    safe at ``Ds = r_i + r_j`` (None: ``safety_radius`` for every pair). With boxes of their
    own, ``A = a_i + a_j`` (each agent's guaranteed deceleration) and ``U = (U_i + U_j) / 2``.

    ``barrier="braking"``: ``h = |dp| - Ds - max(0, -q)^2 / (2 A)`` with ``A = 2 a_max`` and
    ``q = dp.dv/|dp|``; ``c = 1``; while closing (``q < 0``)
    ``RHS = (|dv|^2 - q^2) - A |dp| + gamma h A |dp| / (-q)``. While opening there is no row,
    unless ``dt`` is given: then the one-step row
    ``RHS = (|dv|^2 - q^2) + 2 |dp| (q + gamma (|dp| - Ds)) / dt``, and for every pair the
    sampled-data bound ``rsvo_env.dynamics.barriers.sampled.sampled_braking_rhs``
    (``h+ >= (1 - gamma dt) h`` at the next sample), the smallest RHS of the three; where that
    bound's reversal term puts it beyond the box, the pair also gets a row keeping its tangential
    relative speed from changing sign within the step (``-e_t.(a_i - a_j) <= w_t / dt``).
    ``barrier="hocbf"``: ``h = |dp|^2 - Ds^2``, ``c = 2``,
    ``RHS = 2 |dv|^2 + 2 (g1 + g2) dp.dv + g1 g2 h``.
    Splits of RHS into ``s_ij + s_ji``: ``paper`` (``omega RHS``), ``sign_aware`` (``omega RHS``
    if ``RHS >= 0`` else ``(1 - omega) RHS``), ``capability`` (sign-aware, clipped to
    ``[-cap_i, RHS + cap_j]`` with ``cap`` the most evasive push the box allows along dp; when
    ``RHS < -(cap_i + cap_j)`` the pair is unrecoverable and each takes ``RHS / 2``).
    """
    gamma, safety_radius, lo, hi, barrier, split, gamma2, dt = spec
    if split not in SPLITS:
        raise ValueError(f"split {shown(split)} is unknown; use one of {SPLITS}")
    n = positions.shape[0]
    dp = positions[I] - positions[J]
    dv = velocities[I] - velocities[J]
    dist = np.linalg.norm(dp, axis=1)
    dpdv = np.einsum("ij,ij->i", dp, dv)
    dv2 = np.einsum("ij,ij->i", dv, dv)
    keep_sign = np.zeros(0, dtype=np.int64)  # pairs that get the tangential row (below)
    # each agent's box: one for all, or one each
    own = np.ndim(lo) == 2
    lo_i, hi_i = (lo[I], hi[I]) if own else (lo, hi)
    lo_j, hi_j = (lo[J], hi[J]) if own else (lo, hi)
    Ds = safety_radius if radii is None else radii[I] + radii[J]
    # each agent's most evasive push along dp over its box: max dp.a_i, max -dp.a_j
    push_i, push_j = box_support(dp, lo_i, hi_i), box_support(-dp, lo_j, hi_j)
    if barrier == "braking":
        A_brake = braking_capability(lo_i, hi_i) + braking_capability(lo_j, hi_j)
        U = 0.5 * (largest_input(lo_i, hi_i) + largest_input(lo_j, hi_j))
        # coincident agents divide by zero here; their NaN rows are flagged below
        q, h, rhs, exists, stuck = braking_rhs(
            dist, dpdv, dv2, Ds, A_brake, U, gamma, dt, push_i + push_j
        )
        c = 1.0
        if len(stuck):
            assert dt is not None  # braking_rhs finds stuck pairs in sampled time only
            keep_sign = stuck
            tangential = _tangential_rows(keep_sign, dp, dv, dist, q, omega_pairs[:, 0], dt)
    else:
        g1 = gamma
        g2 = gamma if gamma2 is None else gamma2
        h = dist * dist - Ds**2
        rhs = 2.0 * dv2 + 2.0 * (g1 + g2) * dpdv + g1 * g2 * h
        c = 2.0
        exists = np.ones(len(I), dtype=bool)
    A_i = -c * dp
    w = omega_pairs[:, 0]
    unrecoverable = np.zeros(len(I), dtype=bool)
    capped = np.zeros(len(I), dtype=bool)
    finite_rhs = np.where(exists, rhs, 0.0)
    if split == "paper":
        s_i = w * finite_rhs
    else:
        s_i = np.where(finite_rhs >= 0.0, w * finite_rhs, (1.0 - w) * finite_rhs)
        if split == "capability":
            cap_i, cap_j = c * push_i, c * push_j
            if len(keep_sign):
                # a pair with the tangential row: each agent's capability is what its box
                # allows along dp without breaking its share of that row, so the share it is
                # given never needs a corner the row forbids (docs/double_integrator.md)
                k, (A_t, s_ti, s_tj) = keep_sign, tangential
                cap_i[k] = support_within(
                    dp[k], lo_i[k] if own else lo, hi_i[k] if own else hi, A_t, s_ti
                )
                cap_j[k] = support_within(
                    -dp[k], lo_j[k] if own else lo, hi_j[k] if own else hi, -A_t, s_tj
                )
            unrecoverable = exists & (finite_rhs < -(cap_i + cap_j))
            clipped = np.clip(s_i, -cap_i, finite_rhs + cap_j)
            capped = exists & ~unrecoverable & (clipped != s_i)
            s_i = np.where(unrecoverable, 0.5 * finite_rhs, clipped)
    s_j = finite_rhs - s_i
    # Coincident agents (|dp| = 0) have no direction to keep apart along and give NaN rows: a
    # row no action satisfies (0 . a <= -1) flags both QPs infeasible instead.
    finite = np.isfinite(s_i) & np.isfinite(s_j) & np.isfinite(A_i).all(axis=1)
    bad = (exists & ~finite) | (dist == 0.0)
    if bad.any():
        A_i = np.where(bad[:, None], 0.0, A_i)
        s_i, s_j = np.where(bad, -1.0, s_i), np.where(bad, -1.0, s_j)
        h = np.where(bad, -Ds, h)
        exists = exists | bad
    if len(keep_sign) == 0:
        flags = PairFlags(exists, unrecoverable, capped)
        return finish(n, I, J, A_i, s_i, s_j, h, lo, hi, flags, cull)
    k, (A_t, s_ti, s_tj) = keep_sign, tangential
    P = len(I)
    rows = finish(
        n,
        np.concatenate([I, I[k]]),
        np.concatenate([J, J[k]]),
        np.concatenate([A_i, A_t]),
        np.concatenate([s_i, s_ti]),
        np.concatenate([s_j, s_tj]),
        np.concatenate([h, h[k]]),
        lo,
        hi,
        PairFlags(
            np.concatenate([exists, np.ones(len(k), dtype=bool)]),
            np.concatenate([unrecoverable, np.zeros(len(k), dtype=bool)]),
            np.concatenate([capped, np.zeros(len(k), dtype=bool)]),
        ),
        cull,
    )
    return replace(rows, pair_h=h, n_pairs=P)
