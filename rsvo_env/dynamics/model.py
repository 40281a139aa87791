"""What a dynamics model is to the rest of the code: the protocol the core, the filter, the
observation and the scenarios call, so that none of them compares a model's name.

A model owns its state update (the exact zero-order-hold step), the name of its input bound
(speed or acceleration), its barrier rows and the radius beyond which none of them can bind
(exact culling), the checks its input box must pass, and the velocity bound its episodes reach.
A new model is one module with a subclass of ``Dynamics`` plus one line in the registry
(``rsvo_env/dynamics/__init__.py``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from rsvo_env.util.planar import clip_each, clip_norm

if TYPE_CHECKING:
    from rsvo_env.geometry.bodies import Bodies
    from rsvo_env.qp.rows import Rows
    from rsvo_env.util.settings import FilterSettings


class Dynamics:
    """Base class of the dynamics models (stateless: one instance serves every filter)."""

    name: ClassVar[str] = ""
    # the scenario parameter that bounds the input: "u_max" (speed) or "a_max" (acceleration)
    limit_name: ClassVar[str] = "u_max"
    # whether the filter's rows need the agents' velocities
    needs_velocities: ClassVar[bool] = False
    # whether the compiled dense filter (rsvo_env.filter.dense) computes this model's rows
    dense_kernel: ClassVar[bool] = False
    # whether its QP projects the nominal onto a set that holds u = 0 while no row has b < 0,
    # so that the solution lies in the disk with diameter [0, nominal]
    # (rsvo_env.filter.projection_disk)
    nominal_disk: ClassVar[bool] = False
    # whether one radius from the smallest weight alone bounds every binding pair
    # (``search_radius``); else the state decides it (``culling_radii``)
    radius_from_weights: ClassVar[bool] = False
    # whether its agents may each have their own body radius (rsvo_env.geometry.bodies), and box
    per_agent_bodies: ClassVar[bool] = False
    per_agent_limits: ClassVar[bool] = True
    # the scenario parameters it owns (a scene of this model takes them): defaults, and those
    # that must be > 0
    scenario_defaults: ClassVar[dict[str, Any]] = {}
    scenario_positive: ClassVar[tuple[str, ...]] = ()
    # the state it carries beyond positions and velocities, each (E, N) and named as the
    # simulator's State and ``SafetyFilter.filter``'s keywords (the unicycle: "headings"): the
    # core, the filter, the renderer and the global state pass them on by these names
    state_fields: ClassVar[tuple[str, ...]] = ()

    def check_scenario(self, params: dict[str, Any], name: str) -> None:
        """Checks relating its scenario parameters to the scene's (``name``: the scenario's)."""

    def body_margin(self, params: dict[str, Any]) -> float:
        """How much the filter enlarges each body (0: bodies as they are). Starts laid out
        ``4`` margins further apart than the bodies need stay in the filter's safe set."""
        return 0.0

    def start_bodies(
        self, starts: NDArray, goals: NDArray, radii: NDArray, params: dict[str, Any]
    ) -> tuple[NDArray, NDArray]:
        """The points and radii the filter's safe set holds apart at the start (each agent
        facing its goal): the positions and bodies themselves, unless the model's rows are on
        points of its own."""
        return starts, radii

    def steered(self, state: Any, params: dict[str, Any]) -> tuple[NDArray, NDArray, NDArray]:
        """The points a scripted controller steers as single integrators, their velocities
        and the radius each body adds (the positions, velocities and 0 here)."""
        return state.positions, state.velocities, np.zeros(())

    def track(
        self, state: Any, velocity: NDArray, params: dict[str, Any], limits: NDArray | None
    ) -> NDArray[np.float64]:
        """The inputs (E, N, 2) that give the steered points (``steered``) the
        ``velocity`` (E, N, 2) a scripted controller asks, within the input bound (``limits``
        (N,) each agent's own, or None: the scene's)."""
        raise NotImplementedError

    def step(
        self, positions: NDArray, velocities: NDArray, u: NDArray, dt: float
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The exact zero-order-hold step: (positions, velocities) after ``dt`` with ``u``."""
        raise NotImplementedError

    def check_box(self, cfg: FilterSettings, lo: NDArray, hi: NDArray) -> None:
        """Refuse an input box under which this model's guarantee does not hold."""

    def box(self, cfg: FilterSettings, lo: NDArray, hi: NDArray) -> tuple[NDArray, NDArray]:
        """The box of the filter's QP from the configured bounds (the same, unless the model
        solves in coordinates of its own)."""
        return lo, hi

    def agent_boxes(self, cfg: FilterSettings, u_max: NDArray) -> tuple[NDArray, NDArray]:
        """Each agent's input box (M, 2) from its own bound ``u_max`` (M,), checked > 0:
        ``[-u_max_i, u_max_i]`` per component (a model with another input box overrides it)."""
        hi = np.repeat(np.asarray(u_max, dtype=np.float64).reshape(-1, 1), 2, axis=1)
        return -hi, hi

    def advance_state(self, state: Any, u: NDArray, dt: float, params: dict[str, Any]) -> None:
        """The simulator's step of ``state`` (the core's State: positions, velocities and the
        model's ``state_fields``) under the inputs ``u`` for ``dt``."""
        state.positions, state.velocities = self.step(state.positions, state.velocities, u, dt)

    def to_controls(
        self,
        actions: NDArray,
        params: dict[str, Any],
        planar: Callable[[NDArray], NDArray],
        limits: NDArray | None,
    ) -> NDArray:
        """Normalised actions to the model's inputs: ``planar`` (the core's map of planar
        actions: the norm clipped to 1, times each agent's limit, out of the goal frame) unless
        the model's actions are of its own; ``limits`` (N,) each agent's input bound, or None
        (every agent has the scenario's)."""
        return planar(actions)

    def to_actions(
        self,
        controls: NDArray,
        params: dict[str, Any],
        planar: Callable[[NDArray], NDArray],
        limits: NDArray | None,
    ) -> NDArray:
        """The inverse of ``to_controls`` (no clipping)."""
        return planar(controls)

    def hold(self, controls: NDArray, params: dict[str, Any], limits: NDArray | None) -> NDArray:
        """Inputs (..., N, 2) held to each agent's bound, as ``to_controls`` holds an action
        (a residual's sum with the scripted command goes through it): the norm clipped to the
        scenario's limit, or to each agent's ``limits`` (N,)."""
        if limits is None:
            return clip_norm(controls, params[self.limit_name])
        return clip_each(controls, limits)

    def filter_state(
        self,
        cfg: FilterSettings,
        lead: tuple[int, ...],
        n: int,
        single: bool,
        bodies: Bodies | None,
        state: dict[str, Any],
    ) -> tuple[Bodies | None, dict[str, NDArray]]:
        """The model's own inputs to ``SafetyFilter.filter`` (``state``: its keywords named by
        ``state_fields``, and ``holonomic``), checked, each naming the field and the agent;
        returns the bodies (changed where the model's inputs change them) and the arrays for
        ``lift``."""
        if state.get("holonomic") is not None:
            raise ValueError(f"holonomic is for the unicycle's mixed crowds, not the {self.name}")
        return bodies, {}

    def lift(
        self,
        cfg: FilterSettings,
        positions: NDArray,
        nominal: NDArray,
        bodies: Bodies,
        **state: NDArray,
    ) -> tuple[NDArray, NDArray, Bodies, NDArray | None]:
        """The points the rows are built on, the nominal in the QP's coordinates, the bodies
        the rows and culling use, and each agent's (cos, sin) that turns its rows into those
        coordinates (None: the QP lives in the world's, as here)."""
        return positions, nominal, bodies, None

    def turn_rows(self, rows: Rows, rotation: NDArray | None) -> Rows:
        """The rows in the QP's coordinates (``lift``'s rotation)."""
        return rows

    def global_fields(self) -> tuple[tuple[str, float, float], ...]:
        """The model's own columns of an agent's block in the global state: name, low, high."""
        return ()

    def global_values(self, state: Any, sel: Any) -> list[NDArray]:
        """Those columns' values (E, N) for the envs ``sel`` of the core's State."""
        return []

    def lower(self, cfg: FilterSettings, actions: NDArray, bodies: Bodies) -> NDArray:
        """The QP's solution back in the model's inputs (inverse of ``lift``'s nominal)."""
        return actions

    def rows(
        self,
        cfg: FilterSettings,
        positions: NDArray,
        velocities: NDArray | None,
        weights: NDArray,
        I: NDArray,
        J: NDArray,
        bodies: Bodies,
    ) -> Rows:
        """Every agent's barrier rows for the pairs (I, J), flat agent indices."""
        raise NotImplementedError

    def obstacle_rows(
        self,
        cfg: FilterSettings,
        positions: NDArray,
        velocities: NDArray | None,
        bodies: Bodies,
        capsules: NDArray,
        n: int,
    ) -> tuple[NDArray, ...]:
        """Every agent's rows against the static obstacles (``rsvo_env.geometry.obstacles``),
        weight 1: offsets, A, b, h, obstacle of each row, and each agent's smallest h over them."""
        raise ValueError(f"obstacles are not available for the {self.name} yet")

    def filter_rows(
        self,
        cfg: FilterSettings,
        positions: NDArray,
        velocities: NDArray | None,
        weights: NDArray,
        I: NDArray,
        J: NDArray,
        bodies: Bodies,
        capsules: NDArray | None,
        n: int,
    ) -> tuple[Rows, NDArray | None]:
        """What the filter solves: every agent's rows (pairs, then obstacles, ``capsules``
        (E, O, 5) or (1, O, 5) or None) and each agent's smallest barrier value against the
        obstacles (None without)."""
        from rsvo_env.qp.rows import with_obstacles

        rows = self.rows(cfg, positions, velocities, weights, I, J, bodies)
        if capsules is None:
            return rows, None
        *obstacle_rows, obstacle_h = self.obstacle_rows(
            cfg, positions, velocities, bodies, capsules, n
        )
        return with_obstacles(rows, *obstacle_rows), obstacle_h

    def culling_radii(
        self,
        cfg: FilterSettings,
        omega_floor: NDArray,
        velocities: NDArray | None,
        bodies: Bodies,
        speed: NDArray | None = None,
    ) -> NDArray[np.float64]:
        """Per agent and weight floor (E, N, K), the distance beyond which none of its rows
        with a positive weight can bind in the current state; ``speed``: each agent's nominal
        speed (E, N), for the models that search by the nominal (``nominal_disk``)."""
        raise NotImplementedError

    def search_radius(self, cfg: FilterSettings, omega_min: float, bodies: Bodies) -> float:
        """The one radius of a pair search from the smallest weight (models with
        ``radius_from_weights``)."""
        raise NotImplementedError

    def barrier_over_all_pairs(self) -> bool:
        """Whether ``min_h`` of a scene must cover every pair, not only those examined."""
        return False

    def reach(self, params: dict[str, Any], limit: float, horizon: float) -> tuple[float, float]:
        """How far (position) and how fast (velocity) an agent can get from rest, or from the
        scenario's start speed, within ``horizon`` seconds under the input bound ``limit``."""
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"

    def __eq__(self, other: object) -> bool:
        return type(self) is type(other)

    def __hash__(self) -> int:
        return hash(type(self))
