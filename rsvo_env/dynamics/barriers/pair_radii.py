"""The double integrator's culling radii under the braking and HOCBF barriers: beyond them none
of an agent's rows can bind (``docs/double_integrator.md``; the backup barrier's are in
``backup``)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray


class WorstPair(NamedTuple):
    """The worst pair's values where bodies and boxes are of their own: ``A`` the smallest
    ``a_i + a_j``, ``U`` the largest input, and for the sampled row's ``R_min`` the smallest
    ``r_i + r_j`` (``Ds_min``) and the largest ``a_i`` (``a_top``)."""

    A: float
    U: float
    Ds_min: float
    a_top: float


def double_integrator_radii(
    omega_floor: NDArray,
    velocities: NDArray,
    gamma: float,
    safety_radius: float,
    lo: NDArray,
    hi: NDArray,
    barrier: str = "braking",
    gamma2: float | None = None,
    dt: float | None = None,
    worst: WorstPair | None = None,
) -> NDArray[np.float64]:
    """Per agent and weight floor (E, N, K), the distance beyond which none of its
    double-integrator rows with a positive weight can bind in the current state
    (``docs/double_integrator.md``).

    Bodies and boxes of their own give the worst pair's values: ``safety_radius`` the largest
    ``r_i + r_j``, and ``worst`` (``WorstPair``); None: those of the one box ``lo``, ``hi``
    and ``safety_radius``.

    A row ``-c dp.a_i <= s_ij`` cannot bind when ``s_ij >= c |dp| U`` (``U`` the box's largest
    speed-change vector). Beyond the radius RHS > 0, where every split gives ``s_ij = omega
    RHS``, and RHS is bounded below with the closing speed ``-q <= V = |v_i| + max_j |v_j|``:
    braking, closing: ``RHS >= |dp| (-A + gamma A (|dp| - Ds - V^2 / (2A)) / V)``; braking with
    ``dt``, opening: ``RHS >= 2 gamma |dp| (|dp| - Ds) / dt``, and the sampled-data row (its
    bound alpha* <= -U / omega, from ``G(-U / omega) >= (1 - gamma dt) h``); hocbf:
    ``RHS >= g1 g2 (|dp|^2 - Ds^2) - 2 (g1 + g2) |dp| V``.
    """
    A, U, Ds_min, a_top = (None, None, None, None) if worst is None else worst
    if U is None:
        U = float(np.hypot(*np.maximum(np.abs(lo), np.abs(hi))))
    speed = np.linalg.norm(velocities, axis=-1)
    V = (speed + speed.max(axis=-1, keepdims=True))[..., None]
    ok = np.isfinite(omega_floor)
    w = np.where(ok & (omega_floor > 0), omega_floor, 1.0)
    if barrier == "braking":
        if A is None:
            A = 2.0 * float(np.min(np.minimum(-lo, hi)))
        r = safety_radius + V * V / (2.0 * A) + V * (U / w + A) / (gamma * A)
        if dt is not None:
            r = np.maximum(r, safety_radius + U * dt / (2.0 * gamma * w))
            # the sampled-data row cannot bind once G(-U / omega) >= (1 - gamma dt) h, with E
            # at most U^2 dt^3 / (2 R_min), R_min = Ds - dt^2 (a_max + U) > 0 (the config's bound)
            low = safety_radius if Ds_min is None else Ds_min
            R_min = low - dt * dt * ((A / 2.0 if a_top is None else a_top) + U)
            e = (U / w + U * U * dt * dt / (2.0 * R_min)) if R_min > 0 else np.inf
            sampled = safety_radius + V / gamma + V * V / (2.0 * A) + U * dt / (2.0 * gamma * w)
            r = np.maximum(r, sampled + (2.0 * V * e + dt * e * e) / (2.0 * A * gamma))
    else:
        g2 = gamma if gamma2 is None else gamma2
        a = w * gamma * g2
        B = 2.0 * w * (gamma + g2) * V + 2.0 * U
        r = (B + np.sqrt(B * B + 4.0 * a * a * safety_radius**2)) / (2.0 * a)
    # the bounds are tight only in exact arithmetic; a pair right at the radius stays examined;
    # a floor at or below 0 binds at any distance
    r = np.where(omega_floor > 0, r * (1.0 + 1e-9), np.inf)
    return np.where(ok, r, 0.0)
