"""The simulation state: arrays of E envs x N agents, and a read-only view of one env.

The core (:class:`rsvo_env.core.Simulator`) is the one writer of :class:`State`. Row ``[e, i]``
of every array is agent i of env e (``possible_agents[i]`` of the adapters).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from rsvo_env.responsibility import Weighting

if TYPE_CHECKING:
    from rsvo_env.core import Simulator


@dataclass
class State:
    """Everything that changes during an episode, batch-first.

    ``positions``, ``velocities``, ``goals``, ``starts``: (E, N, 2); ``theta``, ``frame_angle``
    (each agent's start-to-goal heading), ``nearest`` (distance to the nearest neighbour),
    ``at_goal``, ``rh_active`` (the right-hand rule turns the agent's nominal), ``reached`` (at its
    goal at least once): (E, N), the first three derived from the current positions once per
    step; ``neighbors``: (E, N, K) local indices of the K nearest neighbours, nearest first;
    ``weighting``: the mode of each env. The weights live in the core's
    :class:`rsvo_env.weights.Weights`.
    """

    positions: NDArray[np.float64]
    velocities: NDArray[np.float64]
    goals: NDArray[np.float64]
    starts: NDArray[np.float64]
    theta: NDArray[np.float64]
    frame_angle: NDArray[np.float64]
    nearest: NDArray[np.float64]
    at_goal: NDArray[np.bool_]
    rh_active: NDArray[np.bool_]
    neighbors: NDArray[np.int64]
    reached: NDArray[np.bool_]
    weighting: list[Weighting]
    # (E, O, 5) each env's obstacles as capsules (rsvo_env.obstacles), O = 0 without
    obstacles: NDArray[np.float64]
    # (E, N) rsvo_env.clearance.contact where bodies differ or obstacles stand, else None
    contact: NDArray[np.float64] | None = None
    # (E, N) headings (radians), for a model that has them (the unicycle)
    headings: NDArray[np.float64] | None = None
    # (E, N) steps since each agent last came closer to its goal (the core's progress clock,
    # rsvo_env.stall), a copy per step; R-ORCA reads it (rsvo_env.rorca.HOLD_SECONDS)
    no_progress: NDArray[np.int64] | None = None

    @classmethod
    def empty(cls, num_envs: int, n: int, k: int, num_obstacles: int = 0) -> State:
        E = num_envs
        return cls(
            positions=np.zeros((E, n, 2)),
            velocities=np.zeros((E, n, 2)),
            goals=np.zeros((E, n, 2)),
            starts=np.zeros((E, n, 2)),
            theta=np.ones((E, n)),
            frame_angle=np.zeros((E, n)),
            nearest=np.full((E, n), np.inf),
            at_goal=np.zeros((E, n), dtype=bool),
            rh_active=np.zeros((E, n), dtype=bool),
            neighbors=np.zeros((E, n, k), dtype=np.int64),
            reached=np.zeros((E, n), dtype=bool),
            weighting=["asymmetric"] * E,
            obstacles=np.zeros((E, num_obstacles, 5)),
            headings=np.zeros((E, n)),
            no_progress=np.zeros((E, n), dtype=np.int64),
        )


def _read_only(a: NDArray) -> NDArray:
    view = a.view()
    view.flags.writeable = False
    return view


class World:
    """Env e of a simulator, seen as one scene: read-only views of its state rows and its
    parameters (``safety_radius``, ``u_max``, ``dt``, ``dynamics``, ``gamma``, ...).

    The views follow the simulator: they always show the current step. Change theta or the
    weighting through :meth:`set_theta` and :meth:`set_weighting`, which go through the core.
    """

    def __init__(self, sim: Simulator, e: int = 0) -> None:
        self._sim, self._e = sim, e

    def _row(self, name: str) -> NDArray:
        return _read_only(getattr(self._sim.state, name)[self._e])

    positions = property(lambda self: self._row("positions"))
    velocities = property(lambda self: self._row("velocities"))
    goals = property(lambda self: self._row("goals"))
    starts = property(lambda self: self._row("starts"))
    theta = property(lambda self: self._row("theta"))
    # (O, 5) the obstacles as capsules, x0, y0, x1, y1, radius (rsvo_env.obstacles)
    obstacles = property(lambda self: self._row("obstacles"))

    @property
    def omega(self) -> NDArray[np.float64]:
        """The (N, N) weight matrix (Thm. 1): the kept one, or computed now from the scores
        for a crowd beyond ``weights.DENSE_MAX`` agents."""
        s = self._sim.state
        return _read_only(
            self._sim.weights.env_matrix(self._e, s.theta[self._e], s.weighting[self._e])
        )

    @property
    def weighting(self) -> Weighting:
        return self._sim.state.weighting[self._e]

    @property
    def n(self) -> int:
        return self._sim.n

    def nearest_distance(self) -> NDArray[np.float64]:
        """Each agent's distance to its nearest neighbour."""
        return self._row("nearest")

    def __getattr__(self, name: str) -> Any:
        # scenario parameters: safety_radius, u_max, dt, dynamics, gamma, goal_tolerance, ...
        sim = self.__dict__.get("_sim")
        if sim is not None and name in sim.world_params:
            return sim.world_params[name]
        raise AttributeError(name)

    def set_theta(self, theta: Any) -> None:
        self._sim.set_theta(self._e, theta)

    def set_weighting(self, weighting: Weighting) -> None:
        self._sim.set_weighting(self._e, weighting)
