"""The double integrator (paper, eq. ``dynamics``): ``p' = v``, ``v' = a``, the input an
acceleration; barriers, splits and their guarantee in ``docs/double_integrator.md``."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from rsvo_env.dynamics import barriers
from rsvo_env.dynamics.barriers.split import SplitBarrier
from rsvo_env.dynamics.model import Dynamics
from rsvo_env.util.planar import clip_each, norm

if TYPE_CHECKING:
    from rsvo_env.qp.rows import Rows
    from rsvo_env.util.settings import FilterSettings


def double_integrator_step(
    p: NDArray[np.float64], v: NDArray[np.float64], a: NDArray[np.float64], dt: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``p+ = p + dt v + dt^2/2 a``, ``v+ = v + dt a``."""
    return p + dt * v + (0.5 * dt * dt) * a, v + dt * a


# the scripted controller approaches its goal at the speed from which braking at this share of
# the acceleration bound stops there: the rest of the bound is left to the filter and the lag
BRAKE_SHARE = 0.5


class DoubleIntegrator(Dynamics):
    """The rows of the barrier ``FilterConfig.barrier`` names (``rsvo_env.dynamics.barriers``):
    the stopping segment's (the default) or the backup's (the stopping disk), with either of
    which every QP is feasible while every h >= 0, walls included; or the braking or HOCBF
    barrier's, split by responsibility (``split``)."""

    name = "double_integrator"
    limit_name = "a_max"
    needs_velocities = True
    per_agent_bodies = True
    # a_max the acceleration bound; the scripted controller tracks its velocity with gain k_v
    # (the scene's u_max is then the speed it asks, not a bound)
    scenario_defaults = {"a_max": 2.0, "k_v": 8.0}
    scenario_positive = ("a_max", "k_v")

    def track(self, state, velocity, params, limits):
        """``a = k_v (v_wanted - v)``, its norm clipped to the acceleration bound, with
        ``v_wanted``'s norm capped at ``sqrt(a_max d)`` (``d`` the distance to the goal): the
        speed from which braking at half the bound stops at the goal. Without the cap a
        double integrator reaches its goal at full speed, overshoots and circles it."""
        a_max = params["a_max"] if limits is None else limits
        cap = np.sqrt(2.0 * BRAKE_SHARE * np.asarray(a_max) * norm(state.goals - state.positions))
        speed = norm(velocity)
        scale = np.where(speed > cap, cap / np.where(speed > 0, speed, 1.0), 1.0)
        return clip_each(params["k_v"] * (velocity * scale[..., None] - state.velocities), a_max)

    def step(self, positions, velocities, u, dt):
        return double_integrator_step(positions, velocities, u, dt)

    def check_box(self, cfg: FilterSettings, lo: NDArray, hi: NDArray) -> None:
        barriers.get(cfg.barrier).check_box(cfg, lo, hi)

    def filter_rows(self, cfg, positions, velocities, weights, I, J, bodies, capsules, n):
        return barriers.get(cfg.barrier).filter_rows(
            cfg, positions, velocities, weights, I, J, bodies, capsules, n
        )

    def rows(self, cfg, positions, velocities, weights, I, J, bodies) -> Rows:
        barrier = barriers.get(cfg.barrier)
        if not isinstance(barrier, SplitBarrier):
            raise ValueError(
                f"the {cfg.barrier} barrier's rows come with each agent's trust box: use "
                "filter_rows"
            )
        return barrier.pair_rows(cfg, positions, velocities, weights, I, J, bodies)

    def culling_radii(self, cfg, omega_floor, velocities, bodies, speed=None):
        return barriers.get(cfg.barrier).culling_radii(cfg, omega_floor, velocities, bodies)

    def reach(self, params: dict[str, Any], limit: float, horizon: float) -> tuple[float, float]:
        v0 = float(params.get("v0", 0.0))
        return v0 * horizon + 0.5 * limit * horizon**2, v0 + limit * horizon
