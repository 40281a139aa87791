"""The braking barrier (``docs/double_integrator.md``, the paper's): ``h = |dp| - Ds -
max(0, -q)^2 / (2 A)``, the gap left after both agents brake; its pair row split by
responsibility (``pair_rows``), exact in sampled time under ``dt^2 (a_max + |u_max|) < Ds``."""

from __future__ import annotations

import numpy as np

from rsvo_env.dynamics.barriers.box import braking_capability, largest_input
from rsvo_env.dynamics.barriers.split import SplitBarrier, check_sampled_pairs
from rsvo_env.util.validation import shown


class Braking(SplitBarrier):
    """The braking barrier (module docstring)."""

    name = "braking"

    def check_box(self, cfg, lo, hi):
        super().check_box(cfg, lo, hi)
        reach = float(braking_capability(lo, hi) + largest_input(lo, hi))
        if cfg.dt is not None and cfg.dt**2 * reach >= cfg.safety_radius:
            # the sampled-data row divides by the gap at the next sample, which h >= 0 keeps
            # above safety_radius - dt^2 (a_max + |U|) (docs/double_integrator.md)
            raise ValueError(
                f"FilterConfig: dt^2 (a_max + |u_max|) = {shown(cfg.dt**2 * reach)} >= "
                f"safety_radius = {shown(cfg.safety_radius)}: the sampled-data guarantee of the "
                "braking barrier needs dt^2 (a_max + |u_max|) < safety_radius"
            )

    def check_bodies(self, cfg, bodies, I, J):
        if cfg.dt is not None:
            check_sampled_pairs(cfg.dt, bodies, I, J)

    def check_circles(self, cfg, bodies, capsules):
        if cfg.dt is None:
            return
        # the worst agent (fastest box, smallest body) against the smallest circle
        reach = float((braking_capability(bodies.lo, bodies.hi) + bodies.speed).max())
        Ds = float(bodies.radii.min()) + float(np.min(capsules[..., 4]))
        if cfg.dt**2 * reach >= Ds:
            raise ValueError(
                f"an obstacle's safe distance r + rho = {shown(Ds)} <= dt^2 (a_max + "
                f"|u_max|) = "
                f"{shown(cfg.dt**2 * reach)}: the sampled-data guarantee needs it larger"
            )
