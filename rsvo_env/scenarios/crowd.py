"""The crowd: N agents with seeded random starts and goals in a square (the stress and scaling
case), drawn by grid dart throwing."""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env import dynamics
from rsvo_env.control.rorca.controller import ROUTED
from rsvo_env.scenarios.base import Scenario


@njit(cache=True)
def _accept(cand, pts, count, spacing, side):
    """Append to ``pts[:count]`` each candidate at least ``spacing`` from every accepted point,
    in order, until ``pts`` is full. A grid of square cells of side at least ``spacing`` makes
    each test look at the 3 x 3 cells around the candidate only, and there are at most about
    4 N cells (N = ``len(pts)``) however sparse the crowd: the points of a cell are chained
    (``head``, ``chain``), so memory is O(N), not O((side / spacing)^2). Returns the new
    count."""
    n = pts.shape[0]
    cells = max(min(int(np.ceil(side / spacing)), int(np.ceil(2.0 * np.sqrt(n)))), 1)
    width = side / cells  # >= spacing
    head = np.full(cells * cells, -1, dtype=np.int64)
    chain = np.full(n, -1, dtype=np.int64)

    def cell(v):
        return min(max(int((v + side / 2) / width), 0), cells - 1)

    for p in range(count):
        c = cell(pts[p, 0]) * cells + cell(pts[p, 1])
        chain[p], head[c] = head[c], p
    s2 = spacing * spacing
    for c in range(cand.shape[0]):
        if count == n:
            break
        x, y = cand[c, 0], cand[c, 1]
        cx, cy = cell(x), cell(y)
        ok = True
        for gx in range(max(cx - 1, 0), min(cx + 2, cells)):
            for gy in range(max(cy - 1, 0), min(cy + 2, cells)):
                q = head[gx * cells + gy]
                while q >= 0 and ok:
                    if (pts[q, 0] - x) ** 2 + (pts[q, 1] - y) ** 2 < s2:
                        ok = False
                    q = chain[q]
        if ok:
            pts[count, 0], pts[count, 1] = x, y
            k = cx * cells + cy
            chain[count], head[k] = head[k], count
            count += 1
    return count


class Crowd(Scenario):
    """N agents with seeded random starts and goals in a square: the stress and scaling case.
    Starts and goals are ``spacing_factor R`` apart in a square of side
    ``side_factor sqrt(N) R``, both grown by the filter's body margin ``m`` (the unicycle's
    look-ahead): ``+ 4 m`` and ``R + 2 m`` in place of ``R``, so that the look-ahead points
    start in the filter's safe set whatever the headings."""

    name = "crowd"
    models = dynamics.NAMES
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
        # R-ORCA routed around knots, its rules set for crowds of 1,000 and 10,000 (its preset)
        **ROUTED,
    }

    @property
    def side(self) -> float:
        R, m = self.params["safety_radius"], self.body_margin
        return self.params["side_factor"] * np.sqrt(self.num_agents) * (R + 2.0 * m)

    @property
    def spacing(self) -> float:
        """How far apart starts (and goals) are at least."""
        return self.params["spacing_factor"] * self.params["safety_radius"] + self.start_clearance

    def _spread(self, rng: np.random.Generator) -> NDArray[np.float64]:
        """N points uniform in the square, pairwise >= spacing apart: dart throwing in batches,
        each candidate accepted in draw order (so the layout is a function of the seed alone)
        against a grid of accepted points, O(N) per batch."""
        n, side, spacing = self.num_agents, self.side, self.spacing
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
