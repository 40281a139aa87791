"""The double integrator (paper, eq. ``dynamics``): ``p' = v``, ``v' = a``, the input an
acceleration; barriers, splits and their guarantee in ``docs/double_integrator.md``."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from rsvo_env.dynamics.model import Dynamics
from rsvo_env.util.planar import clip_each, norm
from rsvo_env.util.validation import shown

if TYPE_CHECKING:
    from rsvo_env.qp.rows import Rows
    from rsvo_env.util.settings import FilterSettings


def double_integrator_step(
    p: NDArray[np.float64], v: NDArray[np.float64], a: NDArray[np.float64], dt: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``p+ = p + dt v + dt^2/2 a``, ``v+ = v + dt a``."""
    return p + dt * v + (0.5 * dt * dt) * a, v + dt * a


def check_sampled_pairs(dt: float, bodies: Any, I: NDArray, J: NDArray) -> None:
    """The sampled-data bound of the braking barrier for each pair of bodies of their own:
    ``dt^2 (A / 2 + U) < r_i + r_j`` (``A = a_i + a_j``, ``U = (U_i + U_j) / 2``), the pair's
    version of the config's ``dt^2 (a_max + |u_max|) < safety_radius``; an error names the pair."""
    from rsvo_env.dynamics.barriers import braking_capability

    a = braking_capability(bodies.lo, bodies.hi)
    reach = 0.5 * (a[I] + a[J] + bodies.speed[I] + bodies.speed[J])
    Ds = bodies.radii[I] + bodies.radii[J]
    bad = dt * dt * reach >= Ds
    if bad.any():
        k = int(np.argmax(bad))
        raise ValueError(
            f"agents {int(I[k])} and {int(J[k])}: dt^2 (A / 2 + U) = "
            f"{shown(dt * dt * reach[k])} >= "
            f"r_i + r_j = {shown(Ds[k])}: the sampled-data guarantee of the braking barrier needs "
            "dt^2 (A / 2 + U) < r_i + r_j (docs/double_integrator.md)"
        )


# the barriers whose rows are met by every agent's backup at once (docs/double_integrator.md)
BACKED = ("segment", "backup")
# the scripted controller approaches its goal at the speed from which braking at this share of
# the acceleration bound stops there: the rest of the bound is left to the filter and the lag
BRAKE_SHARE = 0.5


def _backed(barrier: str):
    """The rows and culling radii of a barrier of ``BACKED``."""
    if barrier == "segment":
        from rsvo_env.dynamics.segment_barrier import segment_radii, segment_rows

        return segment_rows, segment_radii
    from rsvo_env.dynamics.backup_barrier import backup_radii, backup_rows

    return backup_rows, backup_radii


class DoubleIntegrator(Dynamics):
    """The stopping-segment barrier's rows (``rsvo_env.dynamics.segment_barrier``, the default)
    or the backup barrier's (``backup_barrier``, the stopping disk): with either every QP is
    feasible while every h >= 0, walls included; or the braking or HOCBF barrier's, split by
    responsibility (``FilterConfig.barrier``, ``split``)."""

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

    def takes_walls(self, barrier: str) -> bool:
        # the braking barrier's proof covers circles only; the segment and backup barriers' any
        # capsule
        return barrier in BACKED

    def check_box(self, cfg: FilterSettings, lo: NDArray, hi: NDArray) -> None:
        if cfg.barrier == "hocbf":
            return
        if not ((lo < 0).all() and (hi > 0).all()):
            raise ValueError(
                f"FilterConfig: the {cfg.barrier} barrier needs u_min < 0 < u_max, got "
                f"u_min = {shown(lo.tolist())}, u_max = {shown(hi.tolist())}"
            )
        if cfg.barrier in BACKED:  # exact in sampled time at any dt
            return
        from rsvo_env.dynamics.barriers import braking_capability, largest_input

        reach = float(braking_capability(lo, hi) + largest_input(lo, hi))
        if cfg.dt is not None and cfg.dt**2 * reach >= cfg.safety_radius:
            # the sampled-data row divides by the gap at the next sample, which h >= 0 keeps
            # above safety_radius - dt^2 (a_max + |U|) (docs/double_integrator.md)
            raise ValueError(
                f"FilterConfig: dt^2 (a_max + |u_max|) = {shown(cfg.dt**2 * reach)} >= "
                f"safety_radius = {shown(cfg.safety_radius)}: the sampled-data guarantee of the "
                "braking barrier needs dt^2 (a_max + |u_max|) < safety_radius"
            )

    def filter_rows(self, cfg, positions, velocities, weights, I, J, bodies, capsules, n):
        if cfg.barrier not in BACKED:
            return super().filter_rows(
                cfg, positions, velocities, weights, I, J, bodies, capsules, n
            )
        return _backed(cfg.barrier)[0](
            positions, velocities, weights, I, J, cfg.gamma, cfg.dt, bodies, capsules, n
        )

    def rows(self, cfg, positions, velocities, weights, I, J, bodies) -> Rows:
        from rsvo_env.dynamics import barriers

        if cfg.barrier in BACKED:
            raise ValueError(
                f"the {cfg.barrier} barrier's rows come with each agent's trust box: use "
                "filter_rows"
            )

        if bodies.uniform:
            lo, hi, radii = cfg.lo, cfg.hi, None
        else:
            lo, hi, radii = bodies.lo, bodies.hi, bodies.radii
            if cfg.dt is not None and cfg.barrier == "braking":
                check_sampled_pairs(cfg.dt, bodies, I, J)
        spec = barriers.BarrierSpec(
            cfg.gamma, cfg.safety_radius, lo, hi, cfg.barrier, cfg.split, cfg.gamma2, cfg.dt
        )
        return barriers.double_integrator_rows(
            positions, velocities, weights, I, J, spec, radii=radii
        )

    def obstacle_rows(self, cfg, positions, velocities, bodies, capsules, n):
        from rsvo_env.dynamics.double_integrator_obstacles import double_integrator_obstacle_rows

        walls = np.any(capsules[..., 0:2] != capsules[..., 2:4], axis=-1)
        if walls.any():
            raise ValueError(
                f"walls are not available for the double_integrator with the {cfg.barrier} "
                "barrier (circles are; the segment and backup barriers take walls): obstacle "
                f"{int(np.nonzero(walls)[-1][0])} is a segment"
            )
        if cfg.dt is not None and cfg.barrier == "braking":
            from rsvo_env.dynamics.barriers import braking_capability

            # the worst agent (fastest box, smallest body) against the smallest circle
            reach = float((braking_capability(bodies.lo, bodies.hi) + bodies.speed).max())
            Ds = float(bodies.radii.min()) + float(capsules[..., 4].min())
            if cfg.dt**2 * reach >= Ds:
                raise ValueError(
                    f"an obstacle's safe distance r + rho = {shown(Ds)} <= dt^2 (a_max + "
                    f"|u_max|) = "
                    f"{shown(cfg.dt**2 * reach)}: the sampled-data guarantee needs it larger"
                )
        return double_integrator_obstacle_rows(cfg, positions, velocities, bodies, capsules, n)

    def culling_radii(self, cfg, omega_floor, velocities, bodies, speed=None):
        from rsvo_env.dynamics.double_integrator_radii import WorstPair, double_integrator_radii

        if cfg.barrier in BACKED:
            E, n = velocities.shape[:2]
            return _backed(cfg.barrier)[1](
                omega_floor,
                velocities,
                cfg.gamma,
                cfg.dt,
                bodies.radii.reshape(E, n),
                bodies.lo.reshape(E, n, 2),
                bodies.hi.reshape(E, n, 2),
                bodies.speed.reshape(E, n),
            )
        if bodies.uniform:
            return double_integrator_radii(
                omega_floor,
                velocities,
                cfg.gamma,
                cfg.safety_radius,
                cfg.lo,
                cfg.hi,
                cfg.barrier,
                cfg.gamma2,
                cfg.dt,
            )
        # bodies and boxes of their own: the radius of the worst pair bounds every pair's
        # (it grows with Ds and U and shrinks with A, docs/double_integrator.md)
        from rsvo_env.dynamics.barriers import braking_capability

        a = braking_capability(bodies.lo, bodies.hi)
        worst = WorstPair(
            A=2.0 * float(a.min()),
            U=float(bodies.speed.max()),
            Ds_min=2.0 * float(bodies.radii.min()),
            a_top=float(a.max()),
        )
        return double_integrator_radii(
            omega_floor,
            velocities,
            cfg.gamma,
            2.0 * float(bodies.radii.max()),
            cfg.lo,
            cfg.hi,
            cfg.barrier,
            cfg.gamma2,
            cfg.dt,
            worst,
        )

    def reach(self, params: dict[str, Any], limit: float, horizon: float) -> tuple[float, float]:
        v0 = float(params.get("v0", 0.0))
        return v0 * horizon + 0.5 * limit * horizon**2, v0 + limit * horizon
