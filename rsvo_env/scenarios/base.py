"""The scenario hooks: the base class every scenario extends, today's behaviour as defaults.

A scenario owns its parameters (every one overridable by keyword; an unknown keyword raises
``TypeError`` naming it) and the hooks the simulation core calls for what differs between
scenarios: initial states (drawn from one env's seeded generator), the scripted nominal
controller, the goal test (success is every agent at its goal), the reward terms, the arena and
the lanes a picture draws. Every hook but ``initial_state`` is batch-first: it takes the core's
state, whose arrays are (E, N, ...), and answers for all envs at once.
"""

from __future__ import annotations

import functools
from typing import Any, ClassVar

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env import control, dynamics
from rsvo_env.control import nominal, stall
from rsvo_env.dynamics import Dynamics
from rsvo_env.geometry.obstacles import Obstacles
from rsvo_env.util.planar import within
from rsvo_env.util.validation import (
    check_count,
    check_positive,
    check_real,
    check_theta,
    check_theta_interval,
    check_values,
    shown,
    unknown_keywords,
)

COMMON_DEFAULTS: dict[str, Any] = {
    "dt": 0.01,
    "goal_tolerance": 0.05,
    "deadlock_resolution": "right_hand",
    # the right-hand rule turns only agents that have come no closer to their goals for this
    # long (s; the stall clock, rsvo_env.control.stall): 0, every agent it fires for; None, the
    # controller's own (Controller.rh_hold)
    "rh_hold": None,
    "theta": None,
    "theta_max": 1000.0,
    # (low, high): each episode draws every agent's theta uniformly from it (env's generator)
    "theta_range": None,
    # the scripted controller, a name in rsvo_env.control's registry (the paper's move-to-goal,
    # Sec. V-A, by default); each controller's own settings join these defaults
    "nominal": "move_to_goal",
}
DEADLOCK_RESOLUTIONS = ("right_hand", "none")


@njit(cache=True)
def reward_terms(before, after, goals, first, progress_w, time_w, goal_w, out):
    """Per agent: ``progress_w (|before - goal| - |after - goal|) - time_w + goal_w first``."""
    for i in range(before.shape[0]):
        bx, by = before[i, 0] - goals[i, 0], before[i, 1] - goals[i, 1]
        ax, ay = after[i, 0] - goals[i, 0], after[i, 1] - goals[i, 1]
        progress = np.sqrt(bx * bx + by * by) - np.sqrt(ax * ax + ay * ay)
        out[i] = progress_w * progress - time_w + goal_w * (1.0 if first[i] else 0.0)


class Scenario:
    """Base class: parameters, initial state, nominal controller, arena."""

    name: ClassVar[str] = ""
    dynamics: str = "single_integrator"  # the class's model; an instance may take another
    defaults: ClassVar[dict[str, Any]] = {}
    # the models a scene takes by ``dynamics=`` (none: only its own, ``dynamics``)
    models: ClassVar[tuple[str, ...]] = ()
    # the scripted controllers a scene takes by ``nominal=`` (none: every registered one)
    controllers: ClassVar[tuple[str, ...]] = ()
    # a scenario laid out for a fixed number of agents (None: any number >= 2)
    fixed_agents: ClassVar[int | None] = None
    # parameters that must be > 0 and >= 0 (each subclass adds its own)
    positive: ClassVar[tuple[str, ...]] = ("dt", "goal_tolerance", "safety_radius", "gamma", "k",
                                           "theta_max", "u_max")  # fmt: skip
    nonnegative: ClassVar[tuple[str, ...]] = (
        "rh_trigger",
        "rh_trigger_factor",
        "rh_hold",
    )

    def __init__(self, **kwargs: Any) -> None:
        self.choose_model(kwargs)
        defaults = self.all_defaults()
        params = dict(defaults)
        unknown = sorted(set(kwargs) - set(params))
        for key in unknown:
            owner = [m.name for m in dynamics.MODELS.values() if key in m.scenario_defaults]
            if owner and self.models:
                raise TypeError(
                    f"{self.name}.{key} is the {owner[0]}'s parameter: give "
                    f"dynamics={shown(owner[0])} too"
                )
        if unknown:
            raise TypeError(unknown_keywords(f"{self.name}()", unknown, params))
        if self.fixed_agents is not None and kwargs.get("num_agents", self.fixed_agents) != (
            self.fixed_agents
        ):
            raise ValueError(
                f"{self.name} is laid out for exactly {self.fixed_agents} agents; "
                f"num_agents = {shown(kwargs['num_agents'])} is not possible (use crowd or "
                "circular_swap for other counts)"
            )
        params.update(kwargs)
        self.params = params
        check_count(params["num_agents"], f"{self.name}.num_agents", 2)
        check_values(self.name, params, defaults)
        for key in (*self.positive, *self.model.scenario_positive):
            if key in params:
                params[key] = check_positive(params[key], f"{self.name}.{key}")
        stall.check_dt(params["dt"], f"{self.name}.dt")
        controller = control.get(params["nominal"], f"{self.name}.nominal")
        if self.controllers and controller.name not in self.controllers:
            raise ValueError(
                f"{self.name}.nominal = {shown(controller.name)}: this scene's scripted "
                f"controller is one of {self.controllers}"
            )
        self.controller = controller
        self.controller_settings = controller.check(params, self.name)
        if params["rh_hold"] is None:
            params["rh_hold"] = controller.rh_hold(self.controller_settings)
        params["rh_hold"] = check_real(params["rh_hold"], f"{self.name}.rh_hold")
        for key in self.nonnegative:
            if key in params and params[key] < 0:
                raise ValueError(f"{self.name}.{key} = {shown(params[key])} must be >= 0")
        params[self.limit_name] = check_positive(
            params[self.limit_name], f"{self.name}.{self.limit_name}"
        )
        if params["deadlock_resolution"] not in DEADLOCK_RESOLUTIONS:
            raise ValueError(
                f"{self.name}.deadlock_resolution = {shown(params['deadlock_resolution'])}; "
                f"use one of {DEADLOCK_RESOLUTIONS}"
            )
        check_count(params["max_steps"], f"{self.name}.max_steps", 1)
        if params["theta"] is not None:
            self.check_theta(params["theta"])
        if params["theta_range"] is not None:
            params["theta_range"] = self._check_theta_range(params["theta_range"])
        self.model.check_scenario(params, self.name)
        self.check()

    def choose_model(self, kwargs: dict[str, Any]) -> None:
        """The model ``dynamics`` names, where the scene takes one (else the class's own)."""
        if self.models:
            given = kwargs.get("dynamics", type(self).dynamics)
            # an instance of a registered model stands for its name (models are stateless)
            if isinstance(given, Dynamics) and dynamics.MODELS.get(given.name) == given:
                given = kwargs["dynamics"] = given.name
            if not isinstance(given, str) or given not in self.models:
                raise ValueError(f"{self.name}.dynamics = {shown(given)}; use one of "
                                 f"{self.models} or an instance of one")  # fmt: skip
            self.dynamics = given  # this scene's model (the class's is the default)

    def all_defaults(self) -> dict[str, Any]:
        """Every parameter's default: the common ones, the model's (``dynamics`` names it where
        the scenario takes any model), the scenario's own."""
        own = {"dynamics": type(self).dynamics} if self.models else {}
        common = {**COMMON_DEFAULTS, **control.settings()}
        return {**common, **self.model.scenario_defaults, **self.defaults, **own}

    def check(self) -> None:
        """Checks that relate parameters of a scenario to one another (a subclass's own)."""

    def _check_theta_range(self, value: Any) -> tuple[float, float]:
        low_high = check_theta_interval(value, f"{self.name}.theta_range", self.params["theta_max"])
        if self.params["theta"] is not None:
            raise ValueError(f"{self.name}: give theta or theta_range, not both")
        return low_high

    # -- parameters the env reads -------------------------------------------------------------
    @functools.cached_property
    def model(self) -> Dynamics:
        """The dynamics model (``dynamics`` names it; looked up once a name, as every step asks
        several times)."""
        return dynamics.get(self.dynamics, f"{self.name}.dynamics")

    def __setattr__(self, name: str, value: Any) -> None:
        if name == "dynamics":  # a new model: looked up again on first use
            self.__dict__.pop("model", None)
        super().__setattr__(name, value)

    @property
    def limit_name(self) -> str:
        return self.model.limit_name

    @property
    def speed(self) -> float:
        """The speed the scripted controller asks (``u_max``: a bound for the single integrator
        and the unicycle, the cruising speed of the double integrator)."""
        return float(self.params["u_max"])

    @property
    def body_margin(self) -> float:
        """How much the filter enlarges each body (the unicycle's look-ahead, else 0)."""
        return self.model.body_margin(self.params)

    @property
    def start_clearance(self) -> float:
        """How much further apart layouts set starts: ``4`` body margins, since each filtered
        point lies up to a margin from its body's centre, whatever the heading, and the
        filter holds the points the two margins further apart."""
        return 4.0 * self.body_margin

    @property
    def num_agents(self) -> int:
        return int(self.params["num_agents"])

    @property
    def u_max(self) -> float:
        """The input bound: speed (single integrator) or acceleration (double integrator)."""
        return float(self.params[self.limit_name])

    def check_theta(self, theta: Any) -> NDArray[np.float64]:
        th = check_theta(theta)
        if th.shape != (self.num_agents,):
            raise ValueError(f"theta has {th.shape[0]} entries, expected {self.num_agents}")
        too_big = th > self.params["theta_max"]
        if too_big.any():
            i = int(np.argmax(too_big))
            raise ValueError(
                f"theta[{i}] = {shown(float(th[i]))} exceeds theta_max = "
                f"{self.params['theta_max']} "
                f"(agent {i}); raise theta_max to allow it"
            )
        return th

    def default_theta(self, rng: np.random.Generator) -> NDArray[np.float64]:
        if self.params["theta"] is not None:
            return self.check_theta(self.params["theta"])
        if self.params["theta_range"] is not None:
            low, high = self.params["theta_range"]
            return rng.uniform(low, high, self.num_agents)
        return np.ones(self.num_agents)

    # -- bodies and obstacles -----------------------------------------------------------------
    @property
    def radii(self) -> NDArray[np.float64]:
        """(N,) body radii: ``safety_radius / 2`` each (a pair safe at ``safety_radius``),
        unless the scenario gives its own."""
        key = (self.num_agents, self.params["safety_radius"])
        if self.__dict__.get("_even_radii_key") != key:  # built once: every scripted step reads it
            radii = np.full(self.num_agents, 0.5 * self.params["safety_radius"])
            radii.flags.writeable = False
            self.__dict__["_even_radii"], self.__dict__["_even_radii_key"] = radii, key
        return self.__dict__["_even_radii"]

    @property
    def agent_limits(self) -> NDArray[np.float64] | None:
        """(N,) each agent's own input bound, or None: every agent has ``u_max``."""
        return None

    @property
    def num_obstacles(self) -> int:
        """How many obstacles (capsules) every episode has (none here)."""
        return 0

    @property
    def max_obstacle_radius(self) -> float:
        """The largest capsule radius any episode's obstacle has (0 without obstacles)."""
        return 0.0

    def obstacles(
        self, rng: np.random.Generator, starts: NDArray, goals: NDArray
    ) -> Obstacles | None:
        """One episode's obstacles, ``num_obstacles`` of them (None: none), drawn from the env's
        generator after the starts and goals."""
        return None

    @property
    def plain(self) -> bool:
        """Identical bodies (``safety_radius / 2``), one input bound, no obstacles: today's fast
        paths."""
        return (
            self.num_obstacles == 0
            and self.agent_limits is None
            and bool(np.all(self.radii == 0.5 * self.params["safety_radius"]))
        )

    # -- what subclasses provide --------------------------------------------------------------
    def initial_state(
        self, rng: np.random.Generator
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """(positions, velocities, goals), each (N, 2)."""
        raise NotImplementedError

    def arena(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """A box (lo, hi) that holds every start and goal, for drawing and observation bounds."""
        raise NotImplementedError

    def lanes(self) -> list[NDArray[np.float64]]:
        """Polylines (K, 2) a picture of the scenario draws under the agents (none here)."""
        return []

    def nominal(self, state: Any, right_hand: bool = True) -> NDArray[np.float64]:
        """Scripted nominal controls (E, N, 2) in physical units: move-to-goal (paper, Sec. V-A)
        plus the right-hand rule (unless ``right_hand`` is False), or the velocity the scripted
        controller (``nominal``) asks toward it (``Controller.nominal``), as the model's inputs
        (``Dynamics.track``)."""
        velocity = self.controller.nominal(state, self, right_hand)
        return self.model.track(state, velocity, self.params, self.agent_limits)

    def command(self, state: Any, preferred: NDArray[np.float64]) -> NDArray[np.float64]:
        """The scripted controller's inputs from the ``preferred`` velocities: the model's
        inputs (``Dynamics.track``) that give its steered points the velocity of ``steer``."""
        return self.model.track(state, self.steer(state, preferred), self.params,
                                self.agent_limits)  # fmt: skip

    def steer(self, state: Any, preferred: NDArray[np.float64]) -> NDArray[np.float64]:
        """The velocity the scripted controller (``nominal``) asks from the ``preferred`` ones
        (``Controller.steer``)."""
        return self.controller.steer(state, preferred, self)

    def move_to_goal(self, state: Any, right_hand: bool, speed: float) -> NDArray[np.float64]:
        """The move-to-goal velocity of norm at most ``speed``, turned by the right-hand rule
        where it is on (unless ``right_hand`` is False)."""
        p = self.params
        turn = self.turns(right_hand)
        return nominal.move_to_goal(
            state.positions,
            state.goals,
            p["k"],
            speed,
            state.rh_active if turn else None,
            p["rh_angle_deg"],
        )

    @property
    def right_hand_on(self) -> bool:
        """Whether the right-hand rule is on (``deadlock_resolution="right_hand"``)."""
        return self.params["deadlock_resolution"] == "right_hand"

    def turns(self, right_hand: bool) -> bool:
        """Whether the right-hand rule turns the move-to-goal command (R-ORCA's preferred
        velocity too: the turn breaks the symmetric jams ORCA's half-planes alone hold)."""
        return right_hand and self.right_hand_on

    def right_hand_active(self, state: Any) -> NDArray[np.bool_]:
        """(E, N): agents whose nominal the right-hand rule turns (always False without it), from
        the state's ``nearest``, ``at_goal`` and stall clock (``rh_hold``)."""
        if not self.right_hand_on:
            return np.zeros(state.nearest.shape, dtype=bool)
        return nominal.right_hand_active(state.nearest, state.at_goal, self.rh_trigger,
                                         state.no_progress, self.params["dt"],
                                         self.params["rh_hold"])  # fmt: skip

    def reward(
        self,
        before: NDArray[np.float64],
        after: NDArray[np.float64],
        goals: NDArray[np.float64],
        first_arrival: NDArray[np.bool_],
        weights: tuple[float, float, float],
    ) -> NDArray[np.float64]:
        """Per-agent reward (E, N): progress toward the goal, a time cost, a goal bonus once."""
        out = np.empty(first_arrival.shape)
        # reshape copies only what is not contiguous already
        reward_terms(
            before.reshape(-1, 2),
            after.reshape(-1, 2),
            goals.reshape(-1, 2),
            first_arrival.reshape(-1),
            *weights,
            out.reshape(-1),
        )
        return out

    @property
    def rh_trigger(self) -> float:
        """Distance under which the right-hand rule fires: given, or a multiple of R."""
        if "rh_trigger_factor" in self.params:
            return self.params["rh_trigger_factor"] * self.params["safety_radius"]
        return float(self.params["rh_trigger"])

    def at_goal(self, positions: NDArray, goals: NDArray) -> NDArray[np.bool_]:
        """(..., N): agents within ``goal_tolerance`` of their goals."""
        return within(positions, goals, self.params["goal_tolerance"])
