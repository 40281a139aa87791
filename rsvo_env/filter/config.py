"""FilterConfig: the filter's parameters, validated once (a bad field raises naming it)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import qpsolvers
from numpy.typing import ArrayLike, NDArray

from rsvo_env import dynamics as models
from rsvo_env.dynamics import barriers
from rsvo_env.responsibility.svo import WEIGHTING_MODES, Weighting
from rsvo_env.util.validation import real_array, shown

DYNAMICS = models.NAMES


def _box_bound(value: ArrayLike, name: str) -> NDArray[np.float64]:
    """A bound of the input box, one number or one per component, as (2,) floats; strings,
    bools and complex numbers are refused (numpy would read ``"3"`` as 3.0 and ``True`` as 1.0).
    Finiteness and order are checked by the caller, on both bounds."""
    arr = real_array(value, f"FilterConfig.{name}")
    if arr.shape not in ((), (2,)):
        raise ValueError(
            f"FilterConfig.{name} has shape {arr.shape}: give one number or one per component (2,)"
        )
    return np.broadcast_to(arr, (2,)).copy()


@dataclass(frozen=True)
class FilterConfig:
    """The filter's parameters, validated once: a bad field raises ``ValueError`` naming it.

    Attributes:
        gamma: The class-K gain of eq. ``cbf`` (> 0); with ``dt`` given, ``gamma * dt <= 1``
            is required, the bound under which the step keeps ``h+ >= (1 - gamma dt) h``.
        safety_radius: The distance two identical bodies keep, centre to centre (> 0); bodies
            of their own radii keep ``r_i + r_j``.
        u_max: Each input component's upper bound (velocity for the single integrator and the
            unicycle, acceleration for the double integrator): one number or one per
            component.
        u_min: Each component's lower bound; None: ``-u_max``.
        dt: The sampling step (s) under which the guarantee holds exactly; None: continuous
            time.
        dynamics: The model, by name (``"single_integrator"``, ``"double_integrator"``,
            ``"unicycle"``) or an instance of ``rsvo_env.dynamics.Dynamics``.
        weighting: ``"asymmetric"`` (R-SVO), ``"symmetric"`` (1/2 each) or a callable
            ``theta -> W`` (see [weight_matrix][rsvo_env.weight_matrix]).
        solver: ``"exact"`` (the compiled 2-D projection) or an installed qpsolvers backend.
        barrier: The double integrator's barrier, a name in the barrier registry
            (``"segment"``, the default; ``"backup"``, ``"braking"``, ``"hocbf"``).
        split: How the split barriers share a pair's row (``"capability"``, ``"sign_aware"``,
            ``"paper"``).
        gamma2: The HOCBF's second gain; None: ``gamma``.
        neighbor_radius: The pairs examined lie within it; None: every pair that can bind.
            Below the computed sensing radius the guarantee is lost and a warning says so.
        lookahead: The unicycle's look-ahead distance; None: the model's default.
        w_max: The unicycle's turn-rate bound; None: the model's default.
    """

    gamma: float = 12.0
    safety_radius: float = 1.0
    u_max: float | tuple[float, float] = 3.0
    u_min: float | tuple[float, float] | None = None
    dt: float | None = None
    dynamics: str | models.Dynamics = "single_integrator"
    weighting: Weighting = "asymmetric"
    solver: str = "exact"
    barrier: str = "segment"
    split: str = "capability"
    gamma2: float | None = None
    neighbor_radius: float | None = None
    lookahead: float | None = None
    w_max: float | None = None
    model: models.Dynamics = field(init=False, repr=False, compare=False)
    lo: NDArray[np.float64] = field(init=False, repr=False, compare=False)
    hi: NDArray[np.float64] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        def positive(name: str, value: object) -> None:
            try:
                ok = (
                    not isinstance(value, (bool, np.bool_, str, bytes))
                    and math.isfinite(float(value))  # type: ignore[arg-type]
                    and float(value) > 0  # type: ignore[arg-type]
                )
            except (TypeError, ValueError):
                ok = False
            if not ok:
                raise ValueError(
                    f"FilterConfig.{name} = {shown(value)} must be a finite number > 0"
                )

        # the model (a name or an instance); ``dynamics`` keeps its name, as reported
        model = models.get(self.dynamics, "FilterConfig.dynamics")
        object.__setattr__(self, "model", model)
        object.__setattr__(self, "dynamics", model.name)
        positive("gamma", self.gamma)
        positive("safety_radius", self.safety_radius)
        if self.gamma2 is not None:
            positive("gamma2", self.gamma2)
        if self.dt is not None:
            positive("dt", self.dt)
            if self.gamma * self.dt > 1.0:
                raise ValueError(
                    f"FilterConfig.gamma * dt = {self.gamma} * {self.dt} = "
                    f"{shown(self.gamma * self.dt)} > 1: the discrete step is then no longer "
                    "guaranteed safe (need gamma * dt <= 1)"
                )
        if self.neighbor_radius is not None:
            positive("neighbor_radius", self.neighbor_radius)
        for name in ("lookahead", "w_max"):
            if getattr(self, name) is not None:
                positive(name, getattr(self, name))
        hi = _box_bound(self.u_max, "u_max")
        lo = -hi if self.u_min is None else _box_bound(self.u_min, "u_min")
        if not (np.isfinite(lo).all() and np.isfinite(hi).all()) or not (lo < hi).all():
            raise ValueError(
                f"FilterConfig needs finite u_min < u_max per component, got "
                f"u_min = {shown(lo.tolist())}, u_max = {shown(hi.tolist())}"
            )
        barriers.get(self.barrier, "FilterConfig.barrier")
        model.check_box(self, lo, hi)
        lo, hi = model.box(self, lo, hi)
        object.__setattr__(self, "lo", lo)
        object.__setattr__(self, "hi", hi)
        if not callable(self.weighting) and self.weighting not in WEIGHTING_MODES:
            raise ValueError(
                f"FilterConfig.weighting = {shown(self.weighting)}; use one of {WEIGHTING_MODES} "
                "or a callable theta -> omega matrix"
            )
        if self.split not in barriers.SPLITS:
            raise ValueError(
                f"FilterConfig.split = {shown(self.split)}; use one of {barriers.SPLITS}"
            )
        if self.solver != "exact" and self.solver not in qpsolvers.available_solvers:
            raise ValueError(
                f"FilterConfig.solver = {shown(self.solver)}; use 'exact' or an installed "
                f"qpsolvers "
                f"solver: {sorted(qpsolvers.available_solvers)}"
            )
