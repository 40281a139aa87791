"""A read-only view of one env of the simulator, as one scene (``env.world``)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from rsvo_env.responsibility.svo import Weighting
from rsvo_env.sim.core import Simulator


def _read_only(a: NDArray) -> NDArray:
    view = a.view()
    view.flags.writeable = False
    return view


class World:
    """Env e of a simulator, seen as one scene: read-only views of its state rows and its
    parameters (``safety_radius``, ``u_max``, ``dt``, ``dynamics``, ``gamma``, ...).

    The views follow the simulator: they always show the current step. Change theta or the
    weighting through ``set_theta`` and ``set_weighting``, which go through the core.
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
    # (O, 5) the obstacles as capsules, x0, y0, x1, y1, radius (rsvo_env.geometry.obstacles)
    obstacles = property(lambda self: self._row("obstacles"))

    @property
    def omega(self) -> NDArray[np.float64]:
        """The (N, N) weight matrix (Thm. 1): the kept one, or computed now from the scores
        for a crowd beyond ``sizes.WEIGHT_MATRIX_MAX_AGENTS`` agents."""
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
