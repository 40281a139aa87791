"""The barriers whose one pair row is split between the two agents by responsibility (the
braking barrier and the HOCBF, ``docs/double_integrator.md``): their rows against pairs
(``pair_rows``) and circles (``circle_rows``), and their culling radii (``pair_radii``)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from rsvo_env.dynamics.barriers.box import braking_capability
from rsvo_env.dynamics.barriers.circle_rows import double_integrator_obstacle_rows
from rsvo_env.dynamics.barriers.interface import Barrier
from rsvo_env.dynamics.barriers.pair_radii import WorstPair, double_integrator_radii
from rsvo_env.dynamics.barriers.pair_rows import BarrierSpec, double_integrator_rows
from rsvo_env.qp.rows import with_obstacles
from rsvo_env.util.validation import shown

if TYPE_CHECKING:
    from rsvo_env.geometry.bodies import Bodies
    from rsvo_env.qp.rows import Rows
    from rsvo_env.util.settings import FilterSettings


class SplitBarrier(Barrier):
    """A pair row ``c (-dp.a_i + dp.a_j) <= RHS`` split into the agents' shares by
    ``FilterConfig.split``; circles only among obstacles (its proof covers no walls)."""

    def check_bodies(self, cfg: FilterSettings, bodies: Bodies, I: NDArray, J: NDArray) -> None:
        """Refuse pairs of bodies and boxes of their own under which the guarantee fails (the
        braking barrier's sampled-data bound)."""

    def check_circles(self, cfg: FilterSettings, bodies: Bodies, capsules: NDArray) -> None:
        """Refuse circles against which the guarantee fails (the braking barrier's
        sampled-data bound)."""

    def pair_rows(
        self,
        cfg: FilterSettings,
        positions: NDArray,
        velocities: NDArray,
        weights: NDArray,
        I: NDArray,
        J: NDArray,
        bodies: Bodies,
    ) -> Rows:
        """Every agent's rows for the pairs (I, J) alone (``Barrier.filter_rows``'s
        arguments)."""
        if bodies.uniform:
            lo, hi, radii = cfg.lo, cfg.hi, None
        else:
            lo, hi, radii = bodies.lo, bodies.hi, bodies.radii
            self.check_bodies(cfg, bodies, I, J)
        spec = BarrierSpec(cfg.gamma, cfg.safety_radius, lo, hi, self.name, cfg.split,
                           cfg.gamma2, cfg.dt)  # fmt: skip
        return double_integrator_rows(positions, velocities, weights, I, J, spec, radii=radii)

    def filter_rows(self, cfg, positions, velocities, weights, I, J, bodies, capsules, n):
        rows = self.pair_rows(cfg, positions, velocities, weights, I, J, bodies)
        if capsules is None:
            return rows, None
        walls = np.any(capsules[..., 0:2] != capsules[..., 2:4], axis=-1)
        if walls.any():
            raise ValueError(
                f"walls are not available for the double_integrator with the {self.name} "
                "barrier (circles are; the segment and backup barriers take walls): obstacle "
                f"{int(np.nonzero(walls)[-1][0])} is a segment"
            )
        self.check_circles(cfg, bodies, capsules)
        *obstacle_rows, obstacle_h = double_integrator_obstacle_rows(
            cfg, positions, velocities, bodies, capsules, n
        )
        return with_obstacles(rows, *obstacle_rows), obstacle_h

    def culling_radii(self, cfg, omega_floor, velocities, bodies):
        args = (cfg.gamma, cfg.safety_radius, cfg.lo, cfg.hi, self.name, cfg.gamma2, cfg.dt)
        if bodies.uniform:
            return double_integrator_radii(omega_floor, velocities, *args)
        # bodies and boxes of their own: the radius of the worst pair bounds every pair's
        # (it grows with Ds and U and shrinks with A, docs/double_integrator.md)
        a = braking_capability(bodies.lo, bodies.hi)
        worst = WorstPair(
            A=2.0 * float(a.min()),
            U=float(bodies.speed.max()),
            Ds_min=2.0 * float(bodies.radii.min()),
            a_top=float(a.max()),
        )
        args = (cfg.gamma, 2.0 * float(bodies.radii.max()), *args[2:])
        return double_integrator_radii(omega_floor, velocities, *args, worst)


def check_sampled_pairs(dt: float, bodies: Bodies, I: NDArray, J: NDArray) -> None:
    """The sampled-data bound of the braking barrier for each pair of bodies of their own:
    ``dt^2 (A / 2 + U) < r_i + r_j`` (``A = a_i + a_j``, ``U = (U_i + U_j) / 2``), the pair's
    version of the config's ``dt^2 (a_max + |u_max|) < safety_radius``; an error names the pair."""
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
