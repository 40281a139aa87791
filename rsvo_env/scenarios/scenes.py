"""Scenes with bodies of their own size and static obstacles (``docs/scenarios.md``):

* ``custom`` (``Scene``): the user's own starts, goals, radii and obstacles, as arrays;
* ``doorway``: two groups cross through the gap of a wall, the classic bottleneck;
* ``obstacle_field``: a crowd crosses a field of random circular obstacles.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from rsvo_env import dynamics
from rsvo_env.control import nominal
from rsvo_env.geometry.bodies import check_per_agent
from rsvo_env.geometry.obstacles import Obstacles
from rsvo_env.scenarios.base import Scenario
from rsvo_env.scenarios.checks import check_scene
from rsvo_env.util.validation import check_count, real_array, shown

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
    """The user's own scene from arrays (the registry's ``custom``).

    Args:
        **kwargs: ``starts``, ``goals`` (N, 2), ``radii`` (N,) body radii (default
            ``safety_radius / 2``), obstacles (``circles`` (C, 3), ``walls`` (W, 2, 2) of
            ``thickness``), any model by ``dynamics`` with its input bound one or one per agent
            (``u_max`` the speed limit of the single integrator and the unicycle, ``a_max`` the
            acceleration limit of the double integrator, whose scripted controller tracks the
            move-to-goal velocity of speed ``u_max`` with gain ``k_v``), and every common
            scenario parameter (``docs/scenarios.md``).

    Raises:
        ValueError: An overlapping start, a start or goal inside an obstacle (naming the
            agent), or a bad value (naming the parameter).
    """

    name = "custom"
    models = dynamics.NAMES
    defaults = {
        **BASE,
        "num_agents": 2,
        "starts": None,
        "goals": None,
        "radii": None,
        "circles": None,
        "walls": None,
        "thickness": 0.1,
    }
    nonnegative = (*Scenario.nonnegative, "thickness")

    def __init__(self, **kwargs: Any) -> None:
        if kwargs.get("starts") is None or kwargs.get("goals") is None:
            raise ValueError("custom: give starts and goals, (N, 2) each")
        starts = _points(kwargs["starts"], "custom.starts", None)
        kwargs.setdefault("num_agents", len(starts))
        self.choose_model(kwargs)
        # the input bound: one, or one per agent (the parameter is then the largest, for the
        # bounds); the single integrator's is u_max, the double integrator's a_max
        limit = self.model.limit_name
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
        pts = [
            self._starts,
            self._goals,
            self._obstacles.capsules[:, :2].reshape(-1, 2),
            self._obstacles.capsules[:, 2:4].reshape(-1, 2),
        ]
        allp = np.concatenate(pts)
        pad = 2.0 * float(self._radii.max()) + float(self._obstacles.capsules[:, 4].max(initial=0))
        return allp.min(axis=0) - pad, allp.max(axis=0) + pad


class Doorway(Scenario):
    """Two groups on either side of a wall cross through its gap to the other side (the
    bottleneck of crowd simulators). The scripted controller heads for its lane of the gap (its
    own half, right-hand traffic), then for the goal; an agent outside the band where a body
    passes through the gap first comes level with its lane on its own side."""

    name = "doorway"
    models = dynamics.NAMES
    positive = (*Scenario.positive, "gap", "wall_half_length", "thickness", "depth")
    defaults = {
        **BASE,
        "num_agents": 8,
        "gap": 4.0,
        "wall_half_length": 12.0,
        "thickness": 0.4,
        "depth": 6.0,
        "max_steps": 4000,
        "nominal": "rorca",
    }

    def check(self) -> None:
        p = self.params
        need = p["safety_radius"] + 2.0 * self.body_margin  # the filter's bodies
        if p["gap"] <= need:
            raise ValueError(
                f"doorway.gap = {shown(p['gap'])} must exceed safety_radius = "
                f"{shown(p['safety_radius'])}"
                + (f" + 2 lookahead = {shown(need)}" if self.body_margin else "")
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
        return Obstacles.of(
            walls=[((0.0, g), (0.0, L)), ((0.0, -L), (0.0, -g))], thickness=p["thickness"]
        )

    def obstacles(self, rng, starts, goals):
        return self._walls()

    def initial_state(self, rng):
        p, n = self.params, self.num_agents
        # room to pass between agents parked at goals (the filter's bodies: enlarged)
        spacing = 2.5 * p["safety_radius"] + self.start_clearance
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
        # an agent not yet level with the gap (its centre within the band where a body passes)
        # first comes level with its lane on its own side: the straight line to the mouth would
        # press it into the wall, where a double integrator's stopping segment pins it
        # (docs/liveness.md); from within the band the line to the mouth stays in it
        R = p["safety_radius"]
        level = np.abs(x[..., 1]) <= 0.5 * p["gap"] - 0.5 * R
        near = np.stack([-side * 1.5 * R, lane], -1)
        mouth = np.where(level[..., None], mouth, near)
        target = np.where(crossed[..., None], goals, mouth)
        rh = state.rh_active if self.turns(right_hand) else None
        return self.command(
            state, nominal.move_to_goal(x, target, p["k"], self.speed, rh, p["rh_angle_deg"])
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
    models = dynamics.NAMES
    positive = (*Scenario.positive, "side")
    defaults = {
        **BASE,
        "num_agents": 10,
        "side": 20.0,
        "num_circles": 8,
        "circle_radius": (0.5, 1.5),
        "max_steps": 3000,
        "nominal": "rorca",
    }

    def check(self) -> None:
        check_count(self.params["num_circles"], "obstacle_field.num_circles", 0)
        lo, hi = self.params["circle_radius"]
        if not 0 < lo <= hi:
            raise ValueError(
                f"obstacle_field.circle_radius = {shown((lo, hi))} needs 0 < low <= high"
            )

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
        spacing = 1.2 * R + self.start_clearance
        if n > 1 and ys[1] - ys[0] < spacing:
            raise ValueError(
                f"obstacle_field: {n} agents do not fit on an edge of side {s} at {shown(spacing)} "
                "apart (1.2 safety radii, and 4 look-ahead distances for unicycles); raise side"
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
