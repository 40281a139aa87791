"""The paper's experiments (Sec. V) and a random crowd, one small class each.

Each is a small subclass of :class:`rsvo_env.scenario.Scenario` with its defaults
(``docs/scenarios.md``) and the hooks it changes.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env import nominal
from rsvo_env.scenario import COMMON_DEFAULTS, DEADLOCK_RESOLUTIONS, Scenario
from rsvo_env.validation import check_count

__all__ = ["COMMON_DEFAULTS", "DEADLOCK_RESOLUTIONS", "SCENARIOS", "Scenario", "make_scenario"]


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


def paired_theta(n: int, egoist: float = 1.0, altruist: float = 2.0) -> list[float]:
    """Scores for the circular swap of ``n`` agents as the paper's game sets them (Sec. V-C):
    altruists (agent 0 first) and egoists alternate around the circle and, ``n`` even, every
    agent swaps places with one of the other kind, its antipode. Where ``n / 2`` is odd (the
    paper's 6) that is plain alternation; where it is even, the second half of the circle takes
    the first half's scores inverted (two seams where neighbours share a score): plain
    alternation would pair every egoist with an egoist."""
    n = check_count(n, "paired_theta: n", 1)
    kinds = [i % 2 == 0 for i in range(n)]  # True: altruist
    if n % 2 == 0:
        kinds = kinds[: n // 2] + [not k for k in kinds[: n // 2]]
    return [altruist if k else egoist for k in kinds]


class CircularSwap(Scenario):
    """N agents on a circle, each to the antipodal point (paper, Sec. V-C, Figs. 5-7)."""

    name = "circular_swap"
    positive = (*Scenario.positive, "circle_radius")
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
        # rotate the whole circle by a uniform random angle each episode (env's generator)
        "random_rotation": False,
        "nominal": "rorca",
    }

    def initial_state(self, rng):
        n = self.num_agents
        angles = 2.0 * np.pi * np.arange(n) / n
        if self.params["random_rotation"]:
            angles = angles + rng.uniform(0.0, 2.0 * np.pi)
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
    positive = (*Scenario.positive, "start_distance", "v_des", "k_v", "k_lat")
    nonnegative = (*Scenario.nonnegative, "v0")
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

    def check(self) -> None:
        merge_y, finish = self.params["merge_point"][1], self.params["finish_y"]
        if not finish > merge_y:
            raise ValueError(
                f"ramp_merge.finish_y = {finish!r} must lie beyond the merge point "
                f"(y = {merge_y!r})"
            )

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

    def nominal(self, state, right_hand=True):
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
    positive = (*Scenario.positive, "spacing_factor", "side_factor")
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
        "nominal": "rorca",
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


from rsvo_env.scenes import Doorway, ObstacleField, Scene  # noqa: E402  (they build on Scenario)
from rsvo_env.unicycle_crowd import UnicycleCrowd  # noqa: E402  (it builds on Crowd)

SCENARIOS: dict[str, type[Scenario]] = {
    cls.name: cls for cls in (PositionSwap, CircularSwap, RampMerge, Crowd, Scene, Doorway,
                              ObstacleField, UnicycleCrowd)
}  # fmt: skip


def make_scenario(scenario: str | Scenario, **kwargs: Any) -> Scenario:
    """A scenario by name (``position_swap``, ``circular_swap``, ``ramp_merge``, ``crowd``,
    ``custom``, ``doorway``, ``obstacle_field``, ``unicycle_crowd``)."""
    if isinstance(scenario, Scenario):
        if kwargs:
            raise TypeError("keyword arguments go to the scenario's constructor, not here")
        return scenario
    if scenario not in SCENARIOS:
        raise ValueError(f"unknown scenario {scenario!r}; use one of {sorted(SCENARIOS)}")
    return SCENARIOS[scenario](**kwargs)
