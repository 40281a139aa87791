"""The braking barrier of a double-integrator pair at the next sample (zero-order hold): the
sampled-data row that keeps ``h+ >= (1 - gamma dt) h`` between two samples, not only its rate at
one (``docs/double_integrator.md``, "Sampled data")."""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray


def sampled_braking_rhs(
    dist: NDArray,
    q: NDArray,
    dv2: NDArray,
    h: NDArray,
    A: float | NDArray,
    U: float | NDArray,
    gamma: float,
    dt: float,
    safety_radius: float | NDArray,
    reversal: bool = True,
) -> NDArray[np.float64]:
    """RHS of the pair row ``-dp.(a_i - a_j) <= RHS`` under which the braking barrier at the
    next sample keeps ``h+ >= (1 - gamma dt) h`` (``docs/double_integrator.md``, sampled data).

    In the frame of dp at the sample (radial r, tangential t), a constant relative acceleration
    alpha gives ``R = |dp| + dt q + dt^2 alpha_r / 2 <= |dp+|`` and a closing speed
    ``-q+ <= max(0, -q - dt alpha_r) + E``, where ``E = dt w_t^2 / (8 R)`` bounds what a
    tangential speed ``w_t`` reversed within the step adds (0 when ``|w_t| >= dt cap_t``). So
    ``h+ >= G(alpha_r) = R + g - Ds - (max(0, -q - dt alpha_r) + E)^2 / (2A)``, increasing in
    ``alpha_r``, where ``g = T_min^2 / (2 rho_max)`` is the least the tangential offset adds to
    ``|dp+| = sqrt(R^2 + T^2)`` over the box: ``G >= (1 - gamma dt) h`` is
    ``alpha_r >= alpha*``, one half-plane. Full braking (``alpha_r = A``) meets it whenever
    ``E = 0`` and ``h >= 0``. ``reversal=False``: E = 0, for actions that cannot reverse the
    tangential speed (``double_integrator_rows`` adds the row that forbids it).
    """
    out = np.empty(len(dist))

    def each(value: float | NDArray) -> NDArray[np.float64]:
        # one value for every pair, or one each (bodies and boxes of their own, obstacles)
        return np.ascontiguousarray(np.broadcast_to(np.asarray(value, float), dist.shape))

    _sampled(dist, q, dv2, h, each(A), each(U), gamma, dt, each(safety_radius), reversal, out)
    return out


@njit(cache=True)
def _sampled(dist, q, dv2, h, A_, U_, gamma, dt, safety_radius, reversal, out):
    """``sampled_braking_rhs``, one pair at a time (NaN in, NaN out)."""
    for p in range(dist.shape[0]):
        d, qp, A, U = dist[p], q[p], A_[p], U_[p]
        window2 = (2.0 * U * dt) ** 2
        wt2 = max(dv2[p] - qp * qp, 0.0)
        R_low = d + dt * qp - dt * dt * U  # the smallest R over the box (|alpha_r| <= 2 U)
        if R_low > 0:
            E = dt * wt2 / (8.0 * R_low) if reversal and wt2 < window2 else 0.0
        else:
            E = np.inf
        c = (1.0 - gamma * dt) * h[p]
        # what the tangential offset T adds to |dp+| = sqrt(R^2 + T^2) at the least
        wt = np.sqrt(wt2)
        T_min = max(dt * wt - dt * dt * U, 0.0)
        rho_max = np.hypot(d + dt * qp + dt * dt * U, dt * wt + dt * dt * U)
        Ds = safety_radius[p] - T_min * T_min / (2.0 * rho_max)
        # closing after the step: y = -q - dt alpha_r > 0 solves y' = y + E,
        # y'^2 / (2A) + dt (y' - E) / 2 = K
        K = d + 0.5 * dt * qp - Ds - c
        disc = (A * dt) ** 2 + 8.0 * A * (K + 0.5 * dt * E)
        y = 0.5 * (-A * dt + np.sqrt(max(disc, 0.0))) - E
        if disc >= 0 and y >= 0:
            alpha = (-qp - y) / dt
        else:
            # opening after the step: G = R - Ds - E^2 / (2A) >= c
            alpha = 2.0 * (c + Ds + E * E / (2.0 * A) - d - dt * qp) / (dt * dt)
            floor = -qp / dt
            if not (alpha >= floor or alpha != alpha):
                alpha = floor
        out[p] = -alpha * d
