"""The standalone R-CBF safety filter: plain arrays in, safe actions out.

``SafetyFilter.filter`` builds every agent's rows (``barriers``) with the responsibility weights
(``responsibility``) and solves every agent's QP (paper, eq. ``qp`` and Algorithm 1) in one batch
(``solvers``). It works on arrays in physical units, so any simulator can call it.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
import qpsolvers
from numpy.typing import ArrayLike, NDArray

from rsvo_env import barriers, solvers
from rsvo_env.neighbors import DENSE_MAX_AGENTS
from rsvo_env.responsibility import (
    WEIGHTING_MODES,
    Weighting,
    min_pair_weight,
    pair_omega,
    validate_weight_matrix,
    weight_matrix,
)
from rsvo_env.validation import check_theta, check_vectors

DYNAMICS = ("single_integrator", "double_integrator")


@dataclass(frozen=True)
class FilterConfig:
    """Validated parameters of the filter; a bad field raises ``ValueError`` naming it.

    ``u_max`` / ``u_min`` bound each input component (velocity for the single integrator,
    acceleration for the double integrator); ``u_min`` defaults to ``-u_max``. ``gamma`` is the
    class-K gain of eq. ``cbf``; with ``dt`` given, ``gamma * dt <= 1`` is required, the bound
    under which the Euler step keeps ``h+ >= (1 - gamma dt) h >= 0`` (DESIGN.md section 3).
    ``neighbor_radius`` limits the pairs examined; below the computed sensing radius the
    guarantee is lost and a warning says so.
    """

    gamma: float = 12.0
    safety_radius: float = 1.0
    u_max: float | tuple[float, float] = 3.0
    u_min: float | tuple[float, float] | None = None
    dt: float | None = None
    dynamics: str = "single_integrator"
    weighting: Weighting = "asymmetric"
    solver: str = "exact"
    barrier: str = "braking"
    split: str = "capability"
    gamma2: float | None = None
    neighbor_radius: float | None = None
    lo: NDArray[np.float64] = field(init=False, repr=False, compare=False)
    hi: NDArray[np.float64] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        def positive(name: str, value: object) -> None:
            try:
                ok = math.isfinite(float(value)) and float(value) > 0  # type: ignore[arg-type]
            except (TypeError, ValueError):
                ok = False
            if not ok:
                raise ValueError(f"FilterConfig.{name} = {value!r} must be a finite number > 0")

        positive("gamma", self.gamma)
        positive("safety_radius", self.safety_radius)
        if self.gamma2 is not None:
            positive("gamma2", self.gamma2)
        if self.dt is not None:
            positive("dt", self.dt)
            if self.gamma * self.dt > 1.0:
                raise ValueError(
                    f"FilterConfig.gamma * dt = {self.gamma} * {self.dt} = "
                    f"{self.gamma * self.dt!r} > 1: the discrete step is then no longer "
                    "guaranteed safe (need gamma * dt <= 1)"
                )
        if self.neighbor_radius is not None:
            positive("neighbor_radius", self.neighbor_radius)
        hi = np.broadcast_to(np.asarray(self.u_max, dtype=np.float64), (2,)).copy()
        if self.u_min is None:
            lo = -hi
        else:
            lo = np.broadcast_to(np.asarray(self.u_min, dtype=np.float64), (2,)).copy()
        if not (np.isfinite(lo).all() and np.isfinite(hi).all()) or not (lo < hi).all():
            raise ValueError(
                f"FilterConfig needs finite u_min < u_max per component, got "
                f"u_min = {lo.tolist()!r}, u_max = {hi.tolist()!r}"
            )
        if self.dynamics == "double_integrator" and self.barrier == "braking":
            if not ((lo < 0).all() and (hi > 0).all()):
                raise ValueError(
                    f"FilterConfig: the braking barrier needs u_min < 0 < u_max, got "
                    f"u_min = {lo.tolist()!r}, u_max = {hi.tolist()!r}"
                )
        object.__setattr__(self, "lo", lo)
        object.__setattr__(self, "hi", hi)
        if self.dynamics not in DYNAMICS:
            raise ValueError(f"FilterConfig.dynamics = {self.dynamics!r}; use one of {DYNAMICS}")
        if not callable(self.weighting) and self.weighting not in WEIGHTING_MODES:
            raise ValueError(
                f"FilterConfig.weighting = {self.weighting!r}; use one of {WEIGHTING_MODES} "
                "or a callable theta -> omega matrix"
            )
        if self.barrier not in barriers.BARRIERS:
            raise ValueError(
                f"FilterConfig.barrier = {self.barrier!r}; use one of {barriers.BARRIERS}"
            )
        if self.split not in barriers.SPLITS:
            raise ValueError(f"FilterConfig.split = {self.split!r}; use one of {barriers.SPLITS}")
        if self.solver != "exact" and self.solver not in qpsolvers.available_solvers:
            raise ValueError(
                f"FilterConfig.solver = {self.solver!r}; use 'exact' or an installed qpsolvers "
                f"solver: {sorted(qpsolvers.available_solvers)}"
            )


@dataclass(frozen=True)
class FilterResult:
    """What the filter decided for each agent (the ``certify_action`` contract: action + flag).

    ``feasible[i]`` is False when agent i's QP had no solution; its action is then the one that
    minimises the largest normalised violation, never the nominal, and ``max_violation[i]`` says
    by how much (metres of half-plane offset, 0 when feasible).
    """

    actions: NDArray[np.float64]
    feasible: NDArray[np.bool_]
    intervention: NDArray[np.float64]
    active: NDArray[np.int64]
    min_h: float
    max_violation: NDArray[np.float64]
    n_rows: NDArray[np.int64]
    n_unrecoverable_pairs: int
    n_capped_shares: int
    rows: barriers.Rows = field(repr=False)


class SafetyFilter:
    """The decentralized responsibility-associated CBF filter (paper, Algorithm 1), batched."""

    def __init__(self, config: FilterConfig | None = None, **kwargs: object) -> None:
        if config is not None and kwargs:
            raise TypeError("pass either a FilterConfig or keyword arguments, not both")
        self.config = config if config is not None else FilterConfig(**kwargs)  # type: ignore[arg-type]
        self._omega_in: object = None
        self._omega_ok = np.zeros((0, 0))
        self._omega_min = 0.5

    def pair_radius(self, theta: NDArray, omega: NDArray | None) -> float:
        """Radius of the pair search: the sensing radius (single integrator) or the user's."""
        cfg = self.config
        if cfg.dynamics == "double_integrator":
            return cfg.neighbor_radius if cfg.neighbor_radius is not None else float("inf")
        if omega is not None:
            if omega is not self._omega_ok:
                n = omega.shape[0]
                self._omega_min = float(omega[~np.eye(n, dtype=bool)].min()) if n > 1 else 0.5
            w_min = self._omega_min
        else:
            w_min = min_pair_weight(theta, cfg.weighting)
        radius = barriers.sensing_radius(w_min, cfg.gamma, cfg.safety_radius, cfg.lo, cfg.hi)
        if cfg.neighbor_radius is not None:
            if cfg.neighbor_radius < radius:
                warnings.warn(
                    f"neighbor_radius = {cfg.neighbor_radius} is below the sensing radius "
                    f"{radius:.6g} beyond which no row can bind: the safety guarantee no longer "
                    "holds",
                    stacklevel=3,
                )
            return cfg.neighbor_radius
        return radius

    def pair_weights(
        self, theta: NDArray, omega: NDArray | None, I: NDArray, J: NDArray
    ) -> NDArray[np.float64]:
        """(P, 2) weights of each pair: omega_IJ and omega_JI (Thm. 1), summing to 1."""
        mode = self.config.weighting
        if omega is None and callable(mode):
            omega = weight_matrix(theta, mode)
        if omega is not None:
            return np.stack([omega[I, J], omega[J, I]], axis=1)
        if mode == "symmetric":
            return np.full((len(I), 2), 0.5)
        w = pair_omega(theta[I], theta[J])
        return np.stack([w, 1.0 - w], axis=1)

    def filter(
        self,
        positions: ArrayLike,
        nominal: ArrayLike,
        theta: ArrayLike,
        velocities: ArrayLike | None = None,
        omega: ArrayLike | None = None,
    ) -> FilterResult:
        """Safe actions for N agents (paper, eq. ``qp`` per agent).

        positions, nominal, velocities: (N, 2) in physical units; theta: (N,) personality
        scores; omega: optional (N, N) weight matrix that replaces the configured weighting
        (the world's ``omega``). Bad input raises ``ValueError`` naming field, agent and value.
        """
        cfg = self.config
        pos = check_vectors(positions, "positions")
        n = pos.shape[0]
        nom = check_vectors(nominal, "nominal", n)
        th = check_theta(theta)
        if th.shape[0] != n:
            raise ValueError(f"theta has {th.shape[0]} entries, expected {n} (one per agent)")
        W = None
        if omega is not None:
            # The world hands the same matrix object every step until theta or the mode changes;
            # validating it once is enough.
            if omega is self._omega_in and self._omega_ok.shape == (n, n):
                W = self._omega_ok
            else:
                W = validate_weight_matrix(np.asarray(omega, dtype=np.float64), n)
                off = ~np.eye(n, dtype=bool)
                self._omega_min = float(W[off].min()) if n > 1 else 0.5
                self._omega_in, self._omega_ok = omega, W
        dense = n <= DENSE_MAX_AGENTS and cfg.neighbor_radius is None
        if dense:
            # Few agents: every pair, and exact culling drops the rows that cannot bind.
            I, J = barriers.all_pairs(n)
        else:
            I, J = barriers.candidate_pairs(pos, self.pair_radius(th, W))
        weights = self.pair_weights(th, W, I, J)
        if cfg.dynamics == "single_integrator":
            min_h = None if dense else barriers.nearest_h(pos, cfg.safety_radius)
            rows = barriers.single_integrator_rows(
                pos, weights, I, J, cfg.gamma, cfg.safety_radius, cfg.lo, cfg.hi, min_h
            )
        else:
            if velocities is None:
                raise ValueError("velocities are required for the double integrator")
            vel = check_vectors(velocities, "velocities", n)
            rows = barriers.double_integrator_rows(
                pos,
                vel,
                weights,
                I,
                J,
                cfg.gamma,
                cfg.safety_radius,
                cfg.lo,
                cfg.hi,
                barrier=cfg.barrier,
                split=cfg.split,
                gamma2=cfg.gamma2,
                dt=cfg.dt,
            )
        actions, feasible, active, violation = solvers.solve(
            cfg.solver, nom, rows.A, rows.b, rows.mask, cfg.lo, cfg.hi
        )
        return FilterResult(
            actions=actions,
            feasible=feasible,
            intervention=np.linalg.norm(actions - nom, axis=1),
            active=active,
            min_h=rows.min_h,
            max_violation=violation,
            n_rows=rows.mask.sum(axis=1),
            n_unrecoverable_pairs=rows.n_unrecoverable_pairs,
            n_capped_shares=rows.n_capped_shares,
            rows=rows,
        )
