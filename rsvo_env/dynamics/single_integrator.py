"""The single integrator (paper, Sec. III-B): ``x' = u``, the input a velocity."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from rsvo_env.dynamics.model import Dynamics
from rsvo_env.util.planar import clip_each
from rsvo_env.util.validation import shown

if TYPE_CHECKING:
    from rsvo_env.qp.rows import Rows
    from rsvo_env.util.settings import FilterSettings


def single_integrator_step(
    x: NDArray[np.float64], u: NDArray[np.float64], dt: float
) -> NDArray[np.float64]:
    """``x+ = x + dt u``."""
    return x + dt * u


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
        from rsvo_env.dynamics import barriers

        return barriers.single_integrator_rows(
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
