"""The paper's experiments (Sec. V), one small class each.

Each is a small subclass of ``rsvo_env.scenarios.base.Scenario`` with its defaults
(``docs/scenarios.md``) and the hooks it changes.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from rsvo_env import dynamics
from rsvo_env.control import nominal
from rsvo_env.dynamics import barriers
from rsvo_env.scenarios.base import Scenario
from rsvo_env.util.validation import check_count, shown


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
    models = dynamics.NAMES
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
    # its scripted controller is the paper's lane follower, which nominal="move_to_goal" names
    controllers = ("move_to_goal",)
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
        # the start (15 m/s, 41 m apart) lies in the stopping-segment barrier's safe set
        # (h = 20.4 m; the disk's h is -9.7 m): every QP feasible, no sample below 5 m. The
        # paper's own braking barrier stays by name; the reproduction runs it explicitly
        "barrier": "segment",
        "split": "capability",
        "finish_y": 130.0,
        "max_steps": 1500,
    }

    def check(self) -> None:
        # the filter's settings the scene names, checked with the filter off too
        for key, names in (("barrier", barriers.names()), ("split", barriers.SPLITS)):
            if not isinstance(self.params[key], str) or self.params[key] not in names:
                raise ValueError(
                    f"ramp_merge.{key} = {shown(self.params[key])}; use one of {names}"
                )
        merge_y, finish = self.params["merge_point"][1], self.params["finish_y"]
        if not finish > merge_y:
            raise ValueError(
                f"ramp_merge.finish_y = {shown(finish)} must lie beyond the merge point "
                f"(y = {shown(merge_y)})"
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
