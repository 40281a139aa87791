"""The single integrator (paper, Sec. III-B): ``x' = u``, the input a velocity, and its
barrier rows (paper, eq. ``qp``)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env.dynamics.model import Dynamics
from rsvo_env.qp.rows import PairFlags, Rows, finish
from rsvo_env.util.planar import clip_each
from rsvo_env.util.validation import shown

if TYPE_CHECKING:
    from rsvo_env.util.settings import FilterSettings


def single_integrator_step(
    x: NDArray[np.float64], u: NDArray[np.float64], dt: float
) -> NDArray[np.float64]:
    """``x+ = x + dt u``."""
    return x + dt * u


@njit(cache=True, inline="always")
def single_integrator_row(xi0, xi1, xj0, xj1, w, gamma, R2):
    """Agent i's row against j (paper, eq. ``qp``): ``A = -2 (x_i - x_j)``,
    ``b = omega_ij gamma h_ij`` with ``h_ij = |x_i - x_j|^2 - R^2``. Returns (ax, ay, b, h)."""
    dx = xi0 - xj0
    dy = xi1 - xj1
    h = (dx * dx + dy * dy) - R2
    return -2.0 * dx, -2.0 * dy, w * gamma * h, h


@njit(cache=True)
def _single_integrator_pairs(x, I, J, w, gamma, radii):
    """Per pair: ``A_i = -2 dx``, ``h = |dx|^2 - (r_i + r_j)^2``, ``b = omega gamma h`` for
    both agents."""
    P = I.shape[0]
    A_i = np.empty((P, 2))
    b_i = np.empty(P)
    b_j = np.empty(P)
    h = np.empty(P)
    for p in range(P):
        i, j = I[p], J[p]
        R = radii[i] + radii[j]
        ax, ay, b_i[p], h[p] = single_integrator_row(
            x[i, 0], x[i, 1], x[j, 0], x[j, 1], w[p, 0], gamma, R * R
        )
        A_i[p, 0] = ax
        A_i[p, 1] = ay
        b_j[p] = w[p, 1] * gamma * h[p]
    return A_i, b_i, b_j, h


def single_integrator_rows(
    positions: NDArray,
    omega_pairs: NDArray,
    I: NDArray,
    J: NDArray,
    gamma: float,
    safety_radius: float | NDArray,
    lo: NDArray,
    hi: NDArray,
    cull: bool = True,
) -> Rows:
    """Rows of the paper's QP (eq. ``qp``, Thm. 1) for the pairs (I, J).

    ``omega_pairs`` (P, 2): column 0 is omega of agent ``I[p]`` against ``J[p]``, column 1 the
    other way round; the two sum to 1, so the two rows sum to eq. ``centralized-cbf``.
    ``safety_radius``: every pair's safe distance, or (n,) body radii (a pair's is
    ``r_i + r_j``); ``lo``, ``hi``: one box (2,) or one per agent (n, 2).
    """
    n = positions.shape[0]
    A_i, b_i, b_j, h = _single_integrator_pairs(
        np.ascontiguousarray(positions, dtype=np.float64),
        I,
        J,
        np.ascontiguousarray(omega_pairs, dtype=np.float64),
        float(gamma),
        body_radii(safety_radius, n),
    )
    none = np.zeros(len(I), dtype=bool)
    return finish(n, I, J, A_i, b_i, b_j, h, lo, hi, PairFlags(~none, none, none), cull)


def body_radii(safety_radius: float | NDArray, n: int) -> NDArray[np.float64]:
    """(n,) body radii: the given ones, or half of one pair distance for every agent (exact:
    ``R / 2 + R / 2 == R``, so identical agents keep the pair distance to the last bit)."""
    if np.ndim(safety_radius) == 0:
        return np.full(n, 0.5 * float(safety_radius))
    return np.ascontiguousarray(safety_radius, dtype=np.float64)


class SingleIntegrator(Dynamics):
    """Rows of the paper's QP (eq. ``qp``), the sensing radius of ``docs/math.md``."""

    name = "single_integrator"
    limit_name = "u_max"
    dense_kernel = True
    nominal_disk = True
    radius_from_weights = True
    per_agent_bodies = True

    def track(self, state, velocity, params, limits):
        """The velocity itself, its norm clipped to each agent's own speed limit if given."""
        return velocity if limits is None else clip_each(velocity, limits)

    def step(self, positions, velocities, u, dt):
        # the velocity of a single integrator is the control it integrated
        return single_integrator_step(positions, u, dt), u.copy()

    def check_box(self, cfg: FilterSettings, lo: NDArray, hi: NDArray) -> None:
        if not ((lo <= 0).all() and (hi >= 0).all()):
            # u = 0 satisfies every row while h >= 0 only if the box holds 0: without it a pair
            # in the safe set can have no safe action
            raise ValueError(
                f"FilterConfig: the single-integrator box must contain 0 (u_min <= 0 <= u_max), "
                f"got u_min = {shown(lo.tolist())}, u_max = {shown(hi.tolist())}"
            )

    def rows(self, cfg, positions, velocities, weights, I, J, bodies) -> Rows:
        return single_integrator_rows(
            positions, weights, I, J, cfg.gamma, bodies.radii, bodies.lo, bodies.hi
        )

    def obstacle_rows(self, cfg, positions, velocities, bodies, capsules, n):
        from rsvo_env.geometry.obstacles import single_integrator_obstacle_rows

        return single_integrator_obstacle_rows(
            positions, bodies.radii, capsules, n, float(cfg.gamma), bodies.lo, bodies.hi, True
        )

    def culling_radii(self, cfg, omega_floor, velocities, bodies, speed=None):
        from rsvo_env.geometry import pairs

        E, n = omega_floor.shape[:2]
        if speed is None:  # the box's: any action may be the solution
            speed = bodies.speed.reshape(E, n)
        return pairs.agent_radii(omega_floor, cfg.gamma, speed, bodies.reach(E, n))

    def search_radius(self, cfg, omega_min, bodies):
        from rsvo_env.geometry import pairs

        # the widest box and the largest pair distance of the scene bound every pair's
        c = np.maximum(np.abs(bodies.lo), np.abs(bodies.hi)).max(axis=0)
        R = 2.0 * float(bodies.r_max.max(initial=0.0))
        return pairs.sensing_radius(omega_min, cfg.gamma, R, -c, c)

    def barrier_over_all_pairs(self) -> bool:
        # h is the squared gap: the nearest pair, examined or not, is the scene's smallest
        return True

    def reach(self, params: dict[str, Any], limit: float, horizon: float) -> tuple[float, float]:
        return limit * horizon, limit
