"""World: the state the env owns and the filter reads (DESIGN.md sections 1-2).

Row i of every array belongs to ``env.possible_agents[i]``. The weighting lives here: the
filter reads ``world.omega``, and ``ResponsibilityWeighting`` sets ``world.weighting``, so the
two wrappers stack in either order.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from rsvo_env.neighbors import nearest_neighbors
from rsvo_env.responsibility import Weighting, weight_matrix
from rsvo_env.validation import check_theta


@dataclass
class World:
    """Positions, velocities, goals, theta and the weight matrix of N agents, plus their limits.

    ``u_max`` is the input bound per component and the norm limit of a nominal action: speed for
    the single integrator, acceleration for the double integrator.
    """

    positions: NDArray[np.float64]
    velocities: NDArray[np.float64]
    goals: NDArray[np.float64]
    theta: NDArray[np.float64]
    safety_radius: float
    u_max: float
    dt: float
    dynamics: str
    gamma: float
    goal_tolerance: float
    barrier: str = "braking"
    split: str = "capability"
    weighting: Weighting = "asymmetric"
    neighbor_k: int = 1
    starts: NDArray[np.float64] = field(init=False)
    omega: NDArray[np.float64] = field(init=False)

    def __post_init__(self) -> None:
        self.starts = self.positions.copy()
        self.omega = weight_matrix(self.theta, self.weighting)
        self._table_for: object = None
        self._table: tuple[NDArray[np.float64], NDArray[np.int64]] = (np.zeros(0), np.zeros(0))

    def neighbors(self, k: int) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """Distances and indices (N, >= k) of at least the k nearest neighbours of every agent
        (at least ``neighbor_k``), nearest first.

        One query per state: the result is kept until ``positions`` is replaced (every step
        assigns a new array), so the observation, the metrics and the right-hand rule share it.
        """
        k = max(k, self.neighbor_k, 1)
        if self._table_for is not self.positions or self._table[1].shape[1] < min(k, self.n - 1):
            self._table = nearest_neighbors(self.positions, k)
            self._table_for = self.positions
        d, idx = self._table
        return d, idx

    def nearest_distance(self) -> NDArray[np.float64]:
        """Each agent's distance to its nearest neighbour (inf for a lone agent)."""
        if self.n < 2:
            return np.full(self.n, np.inf)
        return self.neighbors(1)[0][:, 0]

    @property
    def n(self) -> int:
        return int(self.positions.shape[0])

    def set_theta(self, theta: NDArray[np.float64]) -> None:
        th = check_theta(theta)
        if th.shape != (self.n,):
            raise ValueError(f"theta has {th.shape[0]} entries, expected {self.n}")
        omega = weight_matrix(th, self.weighting)
        self.theta, self.omega = th, omega

    def set_weighting(self, weighting: Weighting) -> None:
        """``"asymmetric"``, ``"symmetric"`` or a callable ``theta -> omega``; validated."""
        omega = weight_matrix(self.theta, weighting)
        self.weighting, self.omega = weighting, omega
