"""The double integrator (paper, eq. ``dynamics``): ``p' = v``, ``v' = a``, the input an
acceleration; barriers, splits and their guarantee in ``docs/double_integrator.md``."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from rsvo_env.dynamics.model import Dynamics

if TYPE_CHECKING:
    from rsvo_env.filter_config import FilterConfig
    from rsvo_env.rows import Rows


def double_integrator_step(
    p: NDArray[np.float64], v: NDArray[np.float64], a: NDArray[np.float64], dt: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``p+ = p + dt v + dt^2/2 a``, ``v+ = v + dt a``."""
    return p + dt * v + (0.5 * dt * dt) * a, v + dt * a


class DoubleIntegrator(Dynamics):
    """The braking or HOCBF barrier rows, split by responsibility (``FilterConfig.barrier``,
    ``split``)."""

    name = "double_integrator"
    limit_name = "a_max"
    needs_velocities = True

    def step(self, positions, velocities, u, dt):
        return double_integrator_step(positions, velocities, u, dt)

    def check_box(self, cfg: FilterConfig, lo: NDArray, hi: NDArray) -> None:
        if cfg.barrier != "braking":
            return
        if not ((lo < 0).all() and (hi > 0).all()):
            raise ValueError(
                f"FilterConfig: the braking barrier needs u_min < 0 < u_max, got "
                f"u_min = {lo.tolist()!r}, u_max = {hi.tolist()!r}"
            )
        reach = float(np.min(np.minimum(-lo, hi)) + np.hypot(*np.maximum(-lo, hi)))
        if cfg.dt is not None and cfg.dt**2 * reach >= cfg.safety_radius:
            # the sampled-data row divides by the gap at the next sample, which h >= 0 keeps
            # above safety_radius - dt^2 (a_max + |U|) (docs/double_integrator.md)
            raise ValueError(
                f"FilterConfig: dt^2 (a_max + |u_max|) = {cfg.dt**2 * reach!r} >= "
                f"safety_radius = {cfg.safety_radius!r}: the sampled-data guarantee of the "
                "braking barrier needs dt^2 (a_max + |u_max|) < safety_radius"
            )

    def rows(self, cfg, positions, velocities, weights, I, J, bodies) -> Rows:
        from rsvo_env import barriers

        return barriers.double_integrator_rows(
            positions, velocities, weights, I, J, cfg.gamma, cfg.safety_radius, cfg.lo, cfg.hi,
            barrier=cfg.barrier, split=cfg.split, gamma2=cfg.gamma2, dt=cfg.dt,
        )  # fmt: skip

    def obstacle_rows(self, cfg, positions, velocities, bodies, capsules, n):
        from rsvo_env.double_integrator_obstacles import double_integrator_obstacle_rows

        walls = np.any(capsules[..., 0:2] != capsules[..., 2:4], axis=-1)
        if walls.any():
            raise ValueError(
                "walls are not available for the double_integrator yet (circles are): obstacle "
                f"{int(np.nonzero(walls)[-1][0])} is a segment"
            )
        if cfg.dt is not None and cfg.barrier == "braking":
            lo, hi = cfg.lo, cfg.hi
            reach = float(np.min(np.minimum(-lo, hi)) + np.hypot(*np.maximum(-lo, hi)))
            Ds = float(bodies.radii.min()) + float(capsules[..., 4].min())
            if cfg.dt**2 * reach >= Ds:
                raise ValueError(
                    f"an obstacle's safe distance r + rho = {Ds!r} <= dt^2 (a_max + |u_max|) = "
                    f"{cfg.dt**2 * reach!r}: the sampled-data guarantee needs it larger"
                )
        return double_integrator_obstacle_rows(cfg, positions, velocities, bodies, capsules, n)

    def culling_radii(self, cfg, omega_floor, velocities, bodies):
        from rsvo_env import pairs

        return pairs.double_integrator_radii(
            omega_floor, velocities, cfg.gamma, cfg.safety_radius, cfg.lo, cfg.hi, cfg.barrier,
            cfg.gamma2, cfg.dt,
        )  # fmt: skip

    def reach(self, params: dict[str, Any], limit: float, horizon: float) -> tuple[float, float]:
        v0 = float(params.get("v0", 0.0))
        return v0 * horizon + 0.5 * limit * horizon**2, v0 + limit * horizon
