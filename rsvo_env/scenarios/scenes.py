"""Scenes with bodies of their own size and static obstacles (``docs/scenarios.md``):

* ``custom`` (:class:`Scene`): the user's own starts, goals, radii and obstacles, as arrays;
* ``doorway``: two groups cross through the gap of a wall, the classic bottleneck;
* ``obstacle_field``: a crowd crosses a field of random circular obstacles.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from rsvo_env.control import nominal
from rsvo_env.geometry.bodies import check_per_agent
from rsvo_env.geometry.obstacles import Obstacles
from rsvo_env.scenarios.base import Scenario
from rsvo_env.scenarios.checks import check_scene
from rsvo_env.util import planar
from rsvo_env.util.validation import check_count, real_array

BASE = {
    "safety_radius": 1.0,
    "u_max": 2.0,
    "k": 2.0,
    "gamma": 10.0,
    "rh_angle_deg": 30.0,
    "rh_trigger_factor": 1.5,
    "max_steps": 2000,
}


def _points(value: Any, name: str, n: int | None) -> NDArray[np.float64]:
    arr = real_array(value, name)
    if arr.ndim != 2 or arr.shape[1] != 2 or (n is not None and len(arr) != n):
        raise ValueError(f"{name} has shape {arr.shape}, expected ({n or 'N'}, 2)")
    bad = ~np.isfinite(arr).all(axis=1)
    if bad.any():
        i = int(np.argmax(bad))
        raise ValueError(f"{name}[{i}] = {arr[i].tolist()} is not finite (agent {i})")
    return arr


class Scene(Scenario):
    """The user's own scene from arrays: ``starts``, ``goals`` (N, 2), ``radii`` (N,) body
    radii (default ``safety_radius / 2``), obstacles (``circles`` (C, 3), ``walls`` (W, 2, 2) of
    ``thickness``), ``dynamics`` ``"single_integrator"`` (``u_max`` the speed limit, one or one
    per agent) or ``"double_integrator"`` (``a_max`` the acceleration limit, one or one per
    agent; the scripted controller tracks the move-to-goal velocity of speed ``u_max`` with gain
    ``k_v``). Validated on construction: an overlapping start, a start or goal inside an
    obstacle raises naming the agent."""

    name = "custom"
    defaults = {**BASE, "num_agents": 2, "starts": None, "goals": None, "radii": None,
                "circles": None, "walls": None, "thickness": 0.1,
                "dynamics": "single_integrator", "a_max": 1.0, "k_v": 2.0}  # fmt: skip
    nonnegative = (*Scenario.nonnegative, "thickness")
    positive = (*Scenario.positive, "u_max", "k_v")
    MODELS = ("single_integrator", "double_integrator")

    def __init__(self, **kwargs: Any) -> None:
        if kwargs.get("starts") is None or kwargs.get("goals") is None:
            raise ValueError("custom: give starts and goals, (N, 2) each")
        starts = _points(kwargs["starts"], "custom.starts", None)
        kwargs.setdefault("num_agents", len(starts))
        name = kwargs.get("dynamics", "single_integrator")
        if name not in self.MODELS:
            raise ValueError(
                f"custom.dynamics = {name!r}; use one of {self.MODELS} (unicycles: the "
                "unicycle_crowd scenario)"
            )
        self.dynamics = name  # this scene's model (the class's is the default)
        # the input bound: one, or one per agent (the parameter is then the largest, for the
        # bounds); the single integrator's is u_max, the double integrator's a_max
        limit = self.model.limit_name
        if limit != "a_max" and "a_max" in kwargs:
            raise TypeError("custom.a_max is the double integrator's: give dynamics too")
        self._limits = None
        if np.ndim(kwargs.get(limit, 0.0)) == 1:
            self._limits = check_per_agent(kwargs[limit], f"custom.{limit}", (len(starts),))
            kwargs[limit] = float(self._limits.max())
        super().__init__(**kwargs)

    def check(self) -> None:
        p, n = self.params, self.num_agents
        self._starts = _points(p["starts"], "custom.starts", n)
        self._goals = _points(p["goals"], "custom.goals", n)
        self._radii = np.full(n, 0.5 * p["safety_radius"])
        if p["radii"] is not None:
            self._radii = check_per_agent(p["radii"], "custom.radii", (n,))
        self._obstacles = Obstacles.of(p["circles"], p["walls"], p["thickness"])
        check_scene(self, self._starts, self._goals, self._obstacles.capsules)

    @property
    def radii(self) -> NDArray[np.float64]:
        return self._radii

    @property
    def agent_limits(self) -> NDArray[np.float64] | None:
        return self._limits

    def nominal(self, state, right_hand=True):
        p = self.params
        if self.model.needs_velocities:
            # an acceleration input: track the move-to-goal velocity, a = k_v (v_goal - v)
            v_goal = self.move_to_goal(state, right_hand, p["u_max"])
            u = p["k_v"] * (v_goal - state.velocities)
            lim = p["a_max"] if self._limits is None else self._limits[:, None]
            return planar.clip_norm(u / lim, 1.0) * lim
        u = super().nominal(state, right_hand)
        if self._limits is None:
            return u
        lim = self._limits[:, None]
        return planar.clip_norm(u / lim, 1.0) * lim  # each agent's own speed limit

    @property
    def num_obstacles(self) -> int:
        return len(self._obstacles)

    @property
    def max_obstacle_radius(self) -> float:
        return float(self._obstacles.capsules[:, 4].max(initial=0.0))

    def obstacles(self, rng, starts, goals):
        return self._obstacles if len(self._obstacles) else None

    def initial_state(self, rng):
        return self._starts.copy(), np.zeros_like(self._starts), self._goals.copy()

    def arena(self):
        pts = [self._starts, self._goals, self._obstacles.capsules[:, :2].reshape(-1, 2),
               self._obstacles.capsules[:, 2:4].reshape(-1, 2)]  # fmt: skip
        allp = np.concatenate(pts)
        pad = 2.0 * float(self._radii.max()) + float(self._obstacles.capsules[:, 4].max(initial=0))
        return allp.min(axis=0) - pad, allp.max(axis=0) + pad


class Doorway(Scenario):
    """Two groups on either side of a wall cross through its gap to the other side (the
    bottleneck of crowd simulators). The scripted controller heads for the gap, then the goal."""

    name = "doorway"
    positive = (*Scenario.positive, "gap", "wall_half_length", "thickness", "depth")
    defaults = {**BASE, "num_agents": 8, "gap": 4.0, "wall_half_length": 12.0, "thickness": 0.4,
                "depth": 6.0, "max_steps": 4000, "nominal": "rorca"}  # fmt: skip

    def check(self) -> None:
        p = self.params
        if p["gap"] <= p["safety_radius"]:
            raise ValueError(
                f"doorway.gap = {p['gap']!r} must exceed safety_radius = {p['safety_radius']!r}"
            )

    @property
    def num_obstacles(self) -> int:
        return 2

    @property
    def max_obstacle_radius(self) -> float:
        return 0.5 * self.params["thickness"]

    def _walls(self) -> Obstacles:
        p = self.params
        g, L = 0.5 * p["gap"], p["wall_half_length"]
        return Obstacles.of(walls=[((0.0, g), (0.0, L)), ((0.0, -L), (0.0, -g))],
                            thickness=p["thickness"])  # fmt: skip

    def obstacles(self, rng, starts, goals):
        return self._walls()

    def initial_state(self, rng):
        p, n = self.params, self.num_agents
        spacing = 2.5 * p["safety_radius"]  # room to pass between agents parked at goals
        left = (n + 1) // 2
        pts = []
        for count, side in ((left, -1.0), (n - left, 1.0)):
            rows = int(np.ceil(np.sqrt(count)))
            k = np.arange(count)
            x = side * (p["depth"] + spacing * (k // rows))
            y = spacing * (k % rows - (rows - 1) / 2)
            pts.append(np.c_[x, y])
        start = np.concatenate(pts)
        start = start + rng.uniform(-0.05, 0.05, start.shape) * p["safety_radius"]
        goals = start * np.array([-1.0, 1.0])
        return start, np.zeros_like(start), goals

    def nominal(self, state, right_hand=True):
        p = self.params
        x, goals = state.positions, state.goals
        # before crossing: aim at the gap's mouth on its own side; after: the goal
        side = np.sign(goals[..., 0])
        crossed = np.sign(x[..., 0]) == side
        # right-hand traffic: each direction keeps to its own half of the gap, just past it
        lane = -side * 0.25 * p["gap"]
        mouth = np.stack([side * p["safety_radius"], lane], -1)
        target = np.where(crossed[..., None], goals, mouth)
        rh = state.rh_active if self.turns(right_hand) else None
        return self.steer(
            state, nominal.move_to_goal(x, target, p["k"], self.u_max, rh, p["rh_angle_deg"])
        )

    def arena(self):
        p = self.params
        w = p["depth"] + 2.5 * p["safety_radius"] * np.sqrt(self.num_agents) + p["safety_radius"]
        h = max(p["wall_half_length"], 1.25 * p["safety_radius"] * np.sqrt(self.num_agents) + 2)
        return np.array([-w, -h]), np.array([w, h])


class ObstacleField(Scenario):
    """A crowd crosses a square field of ``num_circles`` random circles (radii in
    ``circle_radius``), starts on the left edge, goals on the right; circles are drawn each
    episode clear of every start and goal."""

    name = "obstacle_field"
    positive = (*Scenario.positive, "side")
    defaults = {**BASE, "num_agents": 10, "side": 20.0, "num_circles": 8,
                "circle_radius": (0.5, 1.5), "max_steps": 3000, "nominal": "rorca"}  # fmt: skip

    def check(self) -> None:
        check_count(self.params["num_circles"], "obstacle_field.num_circles", 0)
        lo, hi = self.params["circle_radius"]
        if not 0 < lo <= hi:
            raise ValueError(f"obstacle_field.circle_radius = {(lo, hi)!r} needs 0 < low <= high")

    @property
    def num_obstacles(self) -> int:
        return int(self.params["num_circles"])

    @property
    def max_obstacle_radius(self) -> float:
        return float(self.params["circle_radius"][1])

    def initial_state(self, rng):
        p, n = self.params, self.num_agents
        s, R = p["side"], p["safety_radius"]
        ys = np.linspace(-s / 2, s / 2, n)
        if n > 1 and ys[1] - ys[0] < 1.2 * R:
            raise ValueError(
                f"obstacle_field: {n} agents do not fit on an edge of side {s} at 1.2 safety "
                "radii apart; raise side"
            )
        start = np.c_[np.full(n, -s / 2 - R), ys]
        goals = np.c_[np.full(n, s / 2 + R), ys[rng.permutation(n)]]
        return start, np.zeros_like(start), goals

    def obstacles(self, rng, starts, goals):
        p = self.params
        lo, hi = p["circle_radius"]
        s, R = p["side"], p["safety_radius"]
        circles = []
        for _ in range(1000 * max(1, self.num_obstacles)):
            if len(circles) == self.num_obstacles:
                break
            c = rng.uniform(-s / 2 + hi, s / 2 - hi, 2)
            r = rng.uniform(lo, hi)
            clear = [np.linalg.norm(c - q[:2]) > r + q[2] + 2 * R for q in circles]
            ends = np.concatenate([starts, goals])
            if all(clear) and (np.linalg.norm(ends - c, axis=1) > r + 2 * R).all():
                circles.append((c[0], c[1], r))
        if len(circles) < self.num_obstacles:
            raise ValueError(f"obstacle_field: could not place {self.num_obstacles} circles")
        return Obstacles.of(circles=circles)

    def arena(self):
        h = self.params["side"] / 2 + 2 * self.params["safety_radius"]
        return np.array([-h, -h]), np.array([h, h])
