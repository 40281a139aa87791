"""The paper's experiments (Sec. V) and a random crowd, one small class each.

A scenario owns its parameters (the defaults of ``docs/scenarios.md``, every one overridable by
keyword; an unknown keyword raises ``TypeError`` naming it) and the hooks the simulation core calls
for what differs between scenarios: initial states (drawn from one env's seeded generator), the
scripted nominal controller, the goal test (success is every agent at its goal), the reward terms
and the arena. Every hook but ``initial_state`` is batch-first: it takes the core's state, whose
arrays are (E, N, ...), and answers for all envs at once.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env import nominal
from rsvo_env.planar import norm
from rsvo_env.validation import check_positive, check_real, check_theta, real_array

COMMON_DEFAULTS: dict[str, Any] = {
    "dt": 0.01,
    "goal_tolerance": 0.05,
    "deadlock_resolution": "right_hand",
    "theta": None,
    "theta_max": 1000.0,
}
DEADLOCK_RESOLUTIONS = ("right_hand", "none")


@njit(cache=True)
def _reward_terms(before, after, goals, first, progress_w, time_w, goal_w, out):
    """Per agent: ``progress_w (|before - goal| - |after - goal|) - time_w + goal_w first``."""
    for i in range(before.shape[0]):
        bx, by = before[i, 0] - goals[i, 0], before[i, 1] - goals[i, 1]
        ax, ay = after[i, 0] - goals[i, 0], after[i, 1] - goals[i, 1]
        progress = np.sqrt(bx * bx + by * by) - np.sqrt(ax * ax + ay * ay)
        out[i] = progress_w * progress - time_w + goal_w * (1.0 if first[i] else 0.0)


class Scenario:
    """Base class: parameters, initial state, nominal controller, arena."""

    name: ClassVar[str] = ""
    dynamics: ClassVar[str] = "single_integrator"
    defaults: ClassVar[dict[str, Any]] = {}
    # a scenario laid out for a fixed number of agents (None: any number >= 2)
    fixed_agents: ClassVar[int | None] = None

    def __init__(self, **kwargs: Any) -> None:
        params = {**COMMON_DEFAULTS, **self.defaults}
        unknown = sorted(set(kwargs) - set(params))
        if unknown:
            raise TypeError(
                f"{self.name}() got unknown keyword argument(s) {unknown}; known: {sorted(params)}"
            )
        if self.fixed_agents is not None and kwargs.get("num_agents", self.fixed_agents) != (
            self.fixed_agents
        ):
            raise ValueError(
                f"{self.name} is laid out for exactly {self.fixed_agents} agents; "
                f"num_agents = {kwargs['num_agents']!r} is not possible (use crowd or "
                "circular_swap for other counts)"
            )
        params.update(kwargs)
        self.params = params
        count = params["num_agents"]
        if isinstance(count, (bool, np.bool_)) or not isinstance(count, (int, np.integer)):
            raise ValueError(f"{self.name}.num_agents = {count!r} must be an integer >= 2")
        if count < 2:
            raise ValueError(f"{self.name}.num_agents = {count!r} must be an integer >= 2")
        for key, default in {**COMMON_DEFAULTS, **self.defaults}.items():
            # every real-valued parameter must be real and finite (a NaN would only surface
            # later, as an error naming no field)
            if isinstance(default, float):
                params[key] = check_real(params[key], f"{self.name}.{key}")
            elif isinstance(default, tuple):
                arr = real_array(params[key], f"{self.name}.{key}")
                if not np.isfinite(arr).all():
                    raise ValueError(f"{self.name}.{key} = {params[key]!r} must be finite")
        for key in ("dt", "goal_tolerance", "safety_radius", "gamma", "k", "theta_max"):
            if key in params:
                params[key] = check_positive(params[key], f"{self.name}.{key}")
        params[self.limit_name] = check_positive(
            params[self.limit_name], f"{self.name}.{self.limit_name}"
        )
        if params["deadlock_resolution"] not in DEADLOCK_RESOLUTIONS:
            raise ValueError(
                f"{self.name}.deadlock_resolution = {params['deadlock_resolution']!r}; "
                f"use one of {DEADLOCK_RESOLUTIONS}"
            )
        steps = params["max_steps"]
        if not isinstance(steps, (int, np.integer)) or steps < 1:
            raise ValueError(f"{self.name}.max_steps = {steps!r} must be an integer >= 1")
        if params["theta"] is not None:
            self.check_theta(params["theta"])

    # -- parameters the env reads -------------------------------------------------------------
    @property
    def limit_name(self) -> str:
        return "a_max" if self.dynamics == "double_integrator" else "u_max"

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
                f"theta[{i}] = {float(th[i])!r} exceeds theta_max = {self.params['theta_max']} "
                f"(agent {i}); raise theta_max to allow it"
            )
        return th

    def default_theta(self, rng: np.random.Generator) -> NDArray[np.float64]:
        if self.params["theta"] is not None:
            return self.check_theta(self.params["theta"])
        return np.ones(self.num_agents)

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

    def nominal(self, state: Any) -> NDArray[np.float64]:
        """Scripted nominal controls (E, N, 2) in physical units: move-to-goal (paper, Sec. V-A)
        plus the right-hand rule."""
        u = nominal.move_to_goal(state.positions, state.goals, self.params["k"], self.u_max)
        if self.params["deadlock_resolution"] == "right_hand":
            u = nominal.right_hand_rule(u, state.rh_active, self.params["rh_angle_deg"])
        return u

    def right_hand_active(self, state: Any) -> NDArray[np.bool_]:
        """(E, N): agents whose nominal the right-hand rule turns (always False without it), from
        the state's ``nearest`` and ``at_goal``."""
        if self.params["deadlock_resolution"] != "right_hand":
            return np.zeros(state.nearest.shape, dtype=bool)
        return nominal.right_hand_active(state.nearest, state.at_goal, self.rh_trigger)

    def reward(
        self,
        before: NDArray[np.float64],
        after: NDArray[np.float64],
        goals: NDArray[np.float64],
        first_arrival: NDArray[np.bool_],
        weights: tuple[float, float, float],
    ) -> NDArray[np.float64]:
        """Per-agent reward (E, N): progress toward the goal, a time cost, a goal bonus once."""
        shape = first_arrival.shape
        out = np.empty(int(np.prod(shape)))
        _reward_terms(
            np.ascontiguousarray(before).reshape(-1, 2),
            np.ascontiguousarray(after).reshape(-1, 2),
            np.ascontiguousarray(goals).reshape(-1, 2),
            np.ascontiguousarray(first_arrival).reshape(-1),
            *weights,
            out,
        )
        return out.reshape(shape)

    @property
    def rh_trigger(self) -> float:
        """Distance under which the right-hand rule fires: given, or a multiple of R."""
        if "rh_trigger_factor" in self.params:
            return self.params["rh_trigger_factor"] * self.params["safety_radius"]
        return float(self.params["rh_trigger"])

    def at_goal(self, positions: NDArray, goals: NDArray) -> NDArray[np.bool_]:
        """(..., N): agents within ``goal_tolerance`` of their goals."""
        return norm(positions - goals) <= self.params["goal_tolerance"]


class PositionSwap(Scenario):
    """Two agents swap corners (paper, Sec. V-A, Fig. 3)."""

    name = "position_swap"
    fixed_agents = 2
    defaults = {
        "num_agents": 2,
        "start": ((-4.0, -4.0), (4.0, 4.0)),
        "safety_radius": 1.0,
        "u_max": 2.0,
        "k": 2.0,
        "gamma": 5.0,
        "rh_angle_deg": 30.0,
        "rh_trigger_factor": 1.5,
        "max_steps": 1500,
    }

    def initial_state(self, rng):
        start = np.array(self.params["start"], dtype=np.float64)
        if start.shape != (self.num_agents, 2):
            raise ValueError(f"position_swap.start has shape {start.shape}, expected (2, 2)")
        return start.copy(), np.zeros_like(start), start[::-1].copy()

    def arena(self):
        start = np.array(self.params["start"], dtype=np.float64)
        pad = 2.0 * self.params["safety_radius"]
        return start.min(axis=0) - pad, start.max(axis=0) + pad


class CircularSwap(Scenario):
    """N agents on a circle, each to the antipodal point (paper, Sec. V-C, Figs. 5-7)."""

    name = "circular_swap"
    defaults = {
        "num_agents": 6,
        "circle_radius": 5.0,
        "safety_radius": 1.0,
        "u_max": 3.0,
        "k": 5.0,
        "gamma": 12.0,
        "rh_angle_deg": 60.0,
        "rh_trigger": 1.1,
        "max_steps": 2000,
    }

    def initial_state(self, rng):
        n = self.num_agents
        angles = 2.0 * np.pi * np.arange(n) / n
        start = self.params["circle_radius"] * np.stack([np.cos(angles), np.sin(angles)], 1)
        return start, np.zeros_like(start), -start

    def arena(self):
        r = self.params["circle_radius"] + 2.0 * self.params["safety_radius"]
        return np.array([-r, -r]), np.array([r, r])


class RampMerge(Scenario):
    """Two vehicles merge from lanes at +-angle onto a main lane (paper, Sec. V-B, Fig. 4).

    Double integrator; the vehicles do not stop: one is ``at_goal`` once past ``finish_y``.
    """

    name = "ramp_merge"
    dynamics = "double_integrator"
    fixed_agents = 2
    defaults = {
        "num_agents": 2,
        "merge_point": (0.0, 70.0),
        "lane_angle_deg": 20.0,
        "start_distance": 60.0,
        "v0": 15.0,
        "v_des": 20.0,
        "k_v": 1.0,
        "k_lat": 1.0,
        "a_max": 5.0,
        "safety_radius": 5.0,
        "gamma": 1.0,
        "barrier": "braking",
        "split": "capability",
        "finish_y": 130.0,
        "max_steps": 1500,
    }

    def lane_starts(self) -> NDArray[np.float64]:
        m = np.array(self.params["merge_point"], dtype=np.float64)
        a = np.deg2rad(self.params["lane_angle_deg"])
        d = self.params["start_distance"]
        return m + d * np.array([[-np.sin(a), -np.cos(a)], [np.sin(a), -np.cos(a)]])

    def lanes(self):
        m = np.array(self.params["merge_point"], dtype=np.float64)
        end = np.array([m[0], self.params["finish_y"]])
        return [np.stack([s, m]) for s in self.lane_starts()] + [np.stack([m, end])]

    def initial_state(self, rng):
        start = self.lane_starts()
        m = np.array(self.params["merge_point"], dtype=np.float64)
        heading = (m - start) / np.linalg.norm(m - start, axis=1, keepdims=True)
        goals = np.array([[m[0], self.params["finish_y"]]] * 2)
        return start, self.params["v0"] * heading, goals

    def arena(self):
        start = self.lane_starts()
        lo = np.array([start[:, 0].min(), start[:, 1].min()]) - 10.0
        hi = np.array([start[:, 0].max(), self.params["finish_y"]]) + 10.0
        return lo, hi

    def nominal(self, state):
        p = self.params
        return nominal.lane_following(
            state.positions,
            state.velocities,
            self.lane_starts(),
            np.array(p["merge_point"], dtype=np.float64),
            p["v_des"],
            p["k_v"],
            p["k_lat"],
            p["a_max"],
        )

    def right_hand_active(self, state):
        return np.zeros(state.nearest.shape, dtype=bool)

    def at_goal(self, positions, goals):
        return positions[..., 1] >= self.params["finish_y"]


@njit(cache=True)
def _accept(cand, pts, count, spacing, side):
    """Append to ``pts[:count]`` each candidate at least ``spacing`` from every accepted point,
    in order, until ``pts`` is full; a grid of cells of side ``spacing`` (at most 4 points each)
    makes each test O(1). Returns the new count."""
    n = pts.shape[0]
    cells = max(int(np.ceil(side / spacing)), 1)
    grid = np.full((cells, cells, 4), -1, dtype=np.int64)

    def cell(v):
        return min(max(int((v + side / 2) / spacing), 0), cells - 1)

    for p in range(count):
        cx, cy = cell(pts[p, 0]), cell(pts[p, 1])
        for s in range(4):
            if grid[cx, cy, s] < 0:
                grid[cx, cy, s] = p
                break
    s2 = spacing * spacing
    for c in range(cand.shape[0]):
        if count == n:
            break
        x, y = cand[c, 0], cand[c, 1]
        cx, cy = cell(x), cell(y)
        ok = True
        for gx in range(max(cx - 1, 0), min(cx + 2, cells)):
            for gy in range(max(cy - 1, 0), min(cy + 2, cells)):
                for s in range(4):
                    q = grid[gx, gy, s]
                    if q >= 0 and (pts[q, 0] - x) ** 2 + (pts[q, 1] - y) ** 2 < s2:
                        ok = False
        if ok:
            pts[count, 0], pts[count, 1] = x, y
            for s in range(4):
                if grid[cx, cy, s] < 0:
                    grid[cx, cy, s] = count
                    break
            count += 1
    return count


class Crowd(Scenario):
    """N agents with seeded random starts and goals in a square: the stress and scaling case."""

    name = "crowd"
    defaults = {
        "num_agents": 12,
        "safety_radius": 1.0,
        "u_max": 2.0,
        "k": 2.0,
        "gamma": 10.0,
        "rh_angle_deg": 30.0,
        "rh_trigger_factor": 1.5,
        "spacing_factor": 1.2,
        "side_factor": 2.5,
        "max_steps": 2000,
    }

    @property
    def side(self) -> float:
        return self.params["side_factor"] * np.sqrt(self.num_agents) * self.params["safety_radius"]

    def _spread(self, rng: np.random.Generator) -> NDArray[np.float64]:
        """N points uniform in the square, pairwise >= spacing apart: dart throwing in batches,
        each candidate accepted in draw order (so the layout is a function of the seed alone)
        against a grid of accepted points, O(N) per batch."""
        n, side = self.num_agents, self.side
        spacing = self.params["spacing_factor"] * self.params["safety_radius"]
        pts = np.empty((n, 2))
        count = 0
        for _ in range(10000):
            cand = rng.uniform(-side / 2, side / 2, (max(2 * (n - count), 8), 2))
            count = _accept(cand, pts, count, spacing, side)
            if count == n:
                return pts
        raise ValueError(
            f"crowd: could not place {n} agents {spacing} apart in a square of side {side:.3g}; "
            "raise side_factor or lower spacing_factor"
        )

    def initial_state(self, rng):
        start = self._spread(rng)
        goals = self._spread(rng)
        return start, np.zeros_like(start), goals

    def arena(self):
        h = self.side / 2 + self.params["safety_radius"]
        return np.array([-h, -h]), np.array([h, h])


SCENARIOS: dict[str, type[Scenario]] = {
    cls.name: cls for cls in (PositionSwap, CircularSwap, RampMerge, Crowd)
}


def make_scenario(scenario: str | Scenario, **kwargs: Any) -> Scenario:
    """A scenario by name (``position_swap``, ``circular_swap``, ``ramp_merge``, ``crowd``)."""
    if isinstance(scenario, Scenario):
        if kwargs:
            raise TypeError("keyword arguments go to the scenario's constructor, not here")
        return scenario
    if scenario not in SCENARIOS:
        raise ValueError(f"unknown scenario {scenario!r}; use one of {sorted(SCENARIOS)}")
    return SCENARIOS[scenario](**kwargs)
