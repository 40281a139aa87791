"""The standalone R-CBF safety filter: plain arrays in, safe actions out.

``SafetyFilter.filter`` builds every agent's rows (``barriers``) with the responsibility weights
(``responsibility``) and solves every agent's QP (paper, eq. ``qp`` and Algorithm 1) in one batch
(``solvers``). It works on arrays in physical units, so any simulator can call it: one scene of
N agents, (N, 2), or E independent scenes at once, (E, N, 2), pairs never crossing scenes. The
simulation core calls ``SafetyFilter.apply``, the same computation without the input checks,
as the stage of its step right before integration.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rsvo_env.filter import dense as dense_solver
from rsvo_env.filter import projection_disk
from rsvo_env.filter import statistics as scene_barrier
from rsvo_env.filter.config import FilterConfig
from rsvo_env.filter.inputs import (
    KnownScenes,
    check_bodies,
    check_obstacles,
)
from rsvo_env.filter.kept_weights import KeptWeights
from rsvo_env.filter.result import FilterResult, per_env
from rsvo_env.geometry import pairs
from rsvo_env.geometry.bodies import Bodies
from rsvo_env.geometry.obstacles import Obstacles
from rsvo_env.qp import solve as solvers
from rsvo_env.qp.rows import Rows
from rsvo_env.responsibility import pair_weights
from rsvo_env.responsibility.pair_weights import Floor
from rsvo_env.responsibility.svo import (
    Weighting,
    min_pair_weight,
    smallest_weight,
    validate_weight_matrix,
    weight_matrix,
)
from rsvo_env.util import sizes
from rsvo_env.util.planar import norm, turn
from rsvo_env.util.validation import check_theta, check_vectors, real_array


class SafetyFilter:
    """The decentralized responsibility-associated CBF filter (paper, Algorithm 1), batched:
    each agent's nominal action projected through its own QP, ``min |u - u_nominal|^2`` within
    its input box and one barrier row per neighbour (and obstacle), ``A_i u <= omega_i b_i``.

    Args:
        config: The filter's parameters; None: ``FilterConfig(**kwargs)``.
        **kwargs: [FilterConfig][rsvo_env.FilterConfig]'s fields, where no ``config`` is
            given.

    Raises:
        TypeError: Both a config and keywords are given.
        ValueError: A bad field (naming it and its value).
    """

    def __init__(self, config: FilterConfig | None = None, **kwargs: object) -> None:
        if config is not None and kwargs:
            raise TypeError("pass either a FilterConfig or keyword arguments, not both")
        self.config = config if config is not None else FilterConfig(**kwargs)  # type: ignore[arg-type]
        # per kind ("floor", "matrix"): the last scores and what the configured weighting
        # gave for them (a simulator calls with the same scores step after step)
        self._weights = KeptWeights(self.config.weighting)
        self._default_bodies: dict[tuple[int, int], Bodies] = {}
        # the last culling radii: (floor, bodies, radii, reach), see _culling_radii
        self._radii: tuple[Floor, Bodies, NDArray, NDArray] | None = None
        # the last floor and its weights times gamma (the search by the nominal)
        self._scaled_floor: tuple[Floor | None, NDArray | None] = (None, None)
        # the agents the last search by the nominal found exempt (likely again: a jam holds)
        self._exempt = np.zeros(0, dtype=bool)

    def pair_radius(
        self,
        theta: NDArray,
        omega: NDArray | None,
        omega_min: NDArray | None = None,
        bodies: Bodies | None = None,
    ) -> float:
        """Radius of the pair search: the sensing radius (single integrator) or the user's.

        Args:
            theta: The scores, (N,) or (E, N).
            omega: The weight matrices, (N, N) or (E, N, N), or None (from ``theta``).
            omega_min: Each scene's smallest weight, where the caller keeps it.
            bodies: Each agent's radius and box; None: the config's.

        Returns:
            The distance beyond which no pair's row can bind (inf for the models whose radius
            comes from the state), or ``neighbor_radius`` where configured.
        """
        cfg = self.config
        if not cfg.model.radius_from_weights:  # the state decides: no radius of the weights
            return cfg.neighbor_radius if cfg.neighbor_radius is not None else float("inf")
        if omega_min is not None:
            w_min = float(np.min(omega_min))
        elif omega is not None:
            w_min = float(np.min(smallest_weight(omega)))
        else:
            th = theta.reshape(-1, theta.shape[-1])
            w_min = min(min_pair_weight(t, cfg.weighting) for t in th)
        if bodies is None:  # the config's: the same radius and box for every agent
            bodies = Bodies.of(cfg, 1, 1)
        radius = cfg.model.search_radius(cfg, w_min, bodies)
        if cfg.neighbor_radius is not None:
            if cfg.neighbor_radius < radius:
                warnings.warn(
                    f"neighbor_radius = {cfg.neighbor_radius} is below the sensing radius "
                    f"{radius:.6g} beyond which no row can bind: the safety guarantee no longer "
                    "holds",
                    stacklevel=4,
                )
            return cfg.neighbor_radius
        return radius

    def pair_weights(
        self,
        theta: NDArray,
        omega: NDArray | None,
        I: NDArray,
        J: NDArray,
        weighting: Sequence[Weighting] | None = None,
    ) -> NDArray[np.float64]:
        """The weights of each pair (Thm. 1): ``omega_IJ`` and ``omega_JI``, summing to 1.

        Args:
            theta: The scores, (N,) or (E, N).
            omega: The weight matrices, (N, N) or (E, N, N), or None (from ``theta``).
            I: The pairs' first agents (P,), flat indices ``e * N + i``.
            J: Their second agents (P,).
            weighting: Each env's named weighting, for scores without a matrix; None: the
                configured one.

        Returns:
            (P, 2) each pair's two weights.
        """
        mode = self.config.weighting
        n = theta.shape[-1]
        if omega is None and weighting is not None:
            return pair_weights.weights_of(theta.reshape(-1, n), weighting, I, J)
        if omega is None and callable(mode):
            omega = weight_matrix(theta, mode)
        if omega is not None:
            return pair_weights.omega_pairs(np.ascontiguousarray(omega).reshape(-1, n), I, J, n)
        if mode == "symmetric":
            return np.full((len(I), 2), 0.5)
        return pair_weights.scored_pairs(theta.reshape(-1, n), I, J)

    def filter(
        self,
        positions: ArrayLike,
        nominal: ArrayLike,
        theta: ArrayLike,
        velocities: ArrayLike | None = None,
        omega: ArrayLike | None = None,
        radii: ArrayLike | None = None,
        u_max: ArrayLike | None = None,
        obstacles: Obstacles | None = None,
        headings: ArrayLike | None = None,
        holonomic: ArrayLike | None = None,
    ) -> FilterResult:
        """Safe actions (paper, eq. ``qp`` per agent) for one scene or a batch of scenes.

        Args:
            positions: (N, 2) or (E, N, 2), in physical units.
            nominal: The nominal actions, the shape of ``positions`` (the unicycle's: (v, w)).
            theta: The personality scores, (N,) or (E, N), >= 0.
            velocities: The velocities, the shape of ``positions`` (the double integrator
                needs them).
            omega: A weight matrix, (N, N) or (E, N, N), in place of the configured weighting
                (validated on every call).
            radii: Body radii, (N,) or (E, N): a pair is safe at ``r_i + r_j``; None:
                ``safety_radius / 2`` each.
            u_max: Each agent's input bound, (N,) or (E, N): the box ``[-u_max_i, u_max_i]``
                per component; None: the config's box.
            obstacles: Static circles and walls ([Obstacles][rsvo_env.Obstacles]), one row each,
                weight 1.
            headings: (N,) or (E, N) radians, for the unicycle (its nominal and actions are
                then (v, w), ``docs/unicycle.md``).
            holonomic: (N,) or (E, N) bools, for the unicycle: the agents that are single
                integrators in a mixed crowd (their nominal and action a world velocity, each
                component within ``u_max``).

        Returns:
            The actions and what the filter decided ([FilterResult][rsvo_env.FilterResult]).

        Raises:
            ValueError: Bad input, naming the field, the agent and the value.
        """
        cfg = self.config
        pos = check_vectors(positions, "positions", lead=None)
        single = pos.ndim == 2
        lead, n = pos.shape[:-2], pos.shape[-2]
        if n < 1:
            raise ValueError("positions has no agents: the filter needs at least one")
        nom = check_vectors(nominal, "nominal", n, lead=lead)
        th = check_theta(theta) if single else real_array(theta, "theta")
        if th.shape != (*lead, n):
            raise ValueError(
                f"theta has shape {th.shape}, expected {(*lead, n)} (one score per agent)"
                if not single
                else f"theta has {th.shape[0]} entries, expected {n} (one per agent)"
            )
        if not single:
            for e in range(lead[0]):
                check_theta(th[e], name=f"theta[{e}]")
        W = None
        if omega is not None:
            W_in = real_array(omega, "omega")
            if W_in.shape != (*lead, n, n):
                raise ValueError(f"omega has shape {W_in.shape}, expected {(*lead, n, n)}")
            W = np.stack([validate_weight_matrix(w, n) for w in W_in.reshape(-1, n, n)])
        bodies = check_bodies(cfg, lead, n, radii, u_max)
        vel = None
        if cfg.model.needs_velocities:
            if velocities is None:
                raise ValueError(f"velocities are required for the {cfg.dynamics}")
            vel = check_vectors(velocities, "velocities", n, lead=lead)
        caps = check_obstacles(obstacles, lead)
        own: dict[str, Any] = {"headings": headings, "holonomic": holonomic}
        bodies, own = cfg.model.filter_state(cfg, lead, n, single, bodies, own)
        kw: dict[str, Any] = {"bodies": bodies, "obstacles": caps, **own}
        if single:
            pos, nom, th = pos[None], nom[None], th[None]
            vel = None if vel is None else vel[None]
        res = self.apply(pos, nom, th, vel, W, **kw)
        if res.rows is None:  # the compiled pass keeps none: built if asked for, from a copy
            p, u, t = pos.copy(), nom.copy(), th.copy()
            v, w = (None if a is None else a.copy() for a in (vel, W))

            def rows_later() -> Rows:
                rows = self.apply(p, u, t, v, w, with_rows=True, **kw).rows
                assert rows is not None  # with_rows keeps them
                return rows

            res.rows_later = rows_later
        return res.squeeze() if single else res

    def apply(
        self,
        positions: NDArray[np.float64],
        nominal: NDArray[np.float64],
        theta: NDArray[np.float64],
        velocities: NDArray[np.float64] | None = None,
        omega: NDArray[np.float64] | None = None,
        with_rows: bool = False,
        known: KnownScenes | None = None,
        weighting: Sequence[Weighting] | None = None,
        bodies: Bodies | None = None,
        obstacles: NDArray | None = None,
        headings: NDArray | None = None,
    ) -> FilterResult:
        """[filter][rsvo_env.SafetyFilter.filter] on (E, N, ...) arrays that are already valid:
        the simulation core's filter stage.

        One call of the row builder and one of the solver serve all E x N agents. Dense
        single-integrator scenes with the exact solver take one compiled pass (the same
        arithmetic) unless ``with_rows`` asks for the rows. Larger scenes examine, for each
        agent, its neighbours within its own radius (``pairs.agent_radii``, or the model's
        ``culling_radii`` from the current velocities): exact culling, so the rows kept, and
        the solution, are those of all pairs.

        Args:
            positions: (E, N, 2).
            nominal: (E, N, 2) the nominal actions.
            theta: (E, N) the scores.
            velocities: (E, N, 2), or None for the models that need none.
            omega: (E, N, N) weight matrices, or None (from ``theta``).
            with_rows: Keep every agent's rows in the result.
            known: What the caller keeps of its scenes (``KnownScenes``: each scene's smallest
                weight, each agent's nearest distance, the weights' floor), which the large-N
                path needs.
            weighting: Each env's weighting; None: the configured one.
            bodies: Each agent's radius and box; None: the config's.
            obstacles: Capsules (O, 5) or (E, O, 5) ([Obstacles][rsvo_env.Obstacles]).
            headings: (E, N) the unicycle's headings (the model's own state).

        Returns:
            The actions and what the filter decided, per env.
        """
        cfg = self.config
        omega_min, nearest, floor = KnownScenes() if known is None else known
        E, n = theta.shape
        if bodies is None:  # the config's, kept: a simulator calls with the same shape
            bodies = self._default_bodies.get((E, n))
            if bodies is None:
                bodies = self._default_bodies[(E, n)] = Bodies.of(cfg, E, n)
        if obstacles is not None and len(obstacles) == 0:
            obstacles = None
        dense = n <= sizes.ALL_PAIRS_MAX_AGENTS and cfg.neighbor_radius is None
        fast = not with_rows and obstacles is None and cfg.model.dense_kernel
        if fast and cfg.solver == "exact" and cfg.neighbor_radius is None:
            if n <= sizes.COMPILED_FILTER_MAX_AGENTS:  # the compiled all-pairs pass
                omega = self._weights.matrix(theta, weighting) if omega is None else omega
                return dense_solver.dense_result(cfg, positions, nominal, omega, bodies)
        solve_box = bodies
        own = {} if headings is None else {"headings": headings}
        positions, solve_nominal, bodies, rotation = cfg.model.lift(
            cfg, positions, nominal, bodies, **own
        )
        disk_nominal = solve_nominal
        if rotation is not None:  # the rows live on points of the model's own (look-ahead)
            nearest = None
            # the rows are built in the world's frame, where the QP's disk is the turned one
            disk_nominal = turn(solve_nominal, *np.moveaxis(rotation.reshape(E, n, 2), -1, 0))
        pos = positions.reshape(E * n, 2)
        vel = None if velocities is None else velocities.reshape(E * n, 2)
        caps = obstacles if obstacles is None or obstacles.ndim == 3 else obstacles[None]

        def rows_of(I: NDArray, J: NDArray) -> tuple[Any, Any]:
            weights = self.pair_weights(theta, omega, I, J, weighting)
            rows, obstacle_h = cfg.model.filter_rows(cfg, pos, vel, weights, I, J, bodies, caps, n)
            return cfg.model.turn_rows(rows, rotation), obstacle_h

        reach, rows = None, None
        if dense:
            # Few agents: every pair, and exact culling drops the rows that cannot bind.
            I, J = pairs.all_pairs(n, E)
        elif cfg.neighbor_radius is None:
            if floor is None:
                floor = self._weights.floor(theta, omega)
            radii, reach = self._culling_radii(floor, velocities, bodies)
            # the search by the nominal pays where the scores spread (an altruist's radius
            # against egoists spans many neighbours); with one group of scores its tests
            # cost more than the pairs they drop (measured: docs/math.md)
            if cfg.model.nominal_disk and floor[0].shape[-1] > 1:
                kept, scaled = self._scaled_floor
                if kept is not floor or scaled is None:  # kept while the floor is
                    scaled = floor[0] * cfg.gamma
                    self._scaled_floor = (floor, scaled)
                likely = self._exempt if self._exempt.shape == (E * n,) else None
                I, J, rows, obstacle_h, reach, self._exempt = projection_disk.search(
                    cfg, positions, disk_nominal, floor, scaled, radii, bodies, rows_of, likely
                )
            else:
                I, J = pairs.pairs_within_agent_radii(positions, radii, floor)
        else:
            radius = self.pair_radius(theta, omega, omega_min, bodies)
            I, J = pairs.candidate_pairs(positions, radius)
        if rows is None:
            rows, obstacle_h = rows_of(I, J)
        if cfg.model.nominal_disk:
            exempt = projection_disk.negative_rows(rows.offsets, rows.flat_b)
            rows = projection_disk.cull(rows, solve_nominal.reshape(-1, 2), exempt)
        actions, feasible, active, violation = solvers.solve(
            cfg.solver,
            solve_nominal.reshape(E * n, 2),
            rows.flat_A,
            rows.flat_b,
            rows.offsets,
            solve_box.lo,
            solve_box.hi,
        )
        actions = cfg.model.lower(cfg, actions, solve_box)
        nom = nominal.reshape(E * n, 2)
        env_of_row = rows.owner // n
        return FilterResult(
            actions=actions.reshape(E, n, 2),
            feasible=feasible.reshape(E, n),
            intervention=norm(actions - nom).reshape(E, n),
            active=active.reshape(E, n),
            min_h=scene_barrier.min_h(
                rows, positions, I, dense, bodies, cfg.model, nearest, reach, obstacle_h
            ),
            max_violation=violation.reshape(E, n),
            n_rows=rows.counts.reshape(E, n),
            n_unrecoverable_pairs=per_env(env_of_row, rows.flat_unrecoverable, E) // 2,
            n_capped_shares=per_env(env_of_row, rows.flat_capped, E),
            kept_rows=rows,
        )

    def _culling_radii(
        self, floor: Floor, velocities: NDArray | None, bodies: Bodies
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Each agent's search radius per score group (E, N, K) and each scene's smallest (E,).
        Radii that do not depend on the state (models without velocities) are kept for the
        floor and bodies they came from: a simulator steps with the same ones, step after step."""
        cfg = self.config
        kept = self._radii
        state_free = not cfg.model.needs_velocities
        if state_free and kept is not None and kept[0] is floor and kept[1] is bodies:
            return kept[2], kept[3]
        radii = cfg.model.culling_radii(cfg, floor[0], velocities, bodies)
        reach = np.where(radii > 0, radii, np.inf).min(axis=(1, 2))
        if state_free:
            self._radii = (floor, bodies, radii, reach)
        return radii, reach
