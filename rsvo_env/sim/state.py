"""The simulation state: arrays of E envs x N agents.

The core (``rsvo_env.sim.core.Simulator``) is the one writer of ``State``. Row ``[e, i]``
of every array is agent i of env e (``possible_agents[i]`` of the adapters).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from rsvo_env.responsibility.svo import Weighting


@dataclass
class State:
    """Everything that changes during an episode, batch-first.

    ``positions``, ``velocities``, ``goals``, ``starts``: (E, N, 2); ``theta``, ``frame_angle``
    (each agent's start-to-goal heading), ``nearest`` (distance to the nearest neighbour),
    ``at_goal``, ``rh_active`` (the right-hand rule turns the agent's nominal), ``reached`` (at its
    goal at least once): (E, N), the first three derived from the current positions once per
    step; ``neighbors``: (E, N, K) local indices of the K nearest neighbours, nearest first;
    ``weighting``: the mode of each env. The weights live in the core's
    ``rsvo_env.sim.weights.Weights``.
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
    # (E, O, 5) each env's obstacles as capsules (rsvo_env.geometry.obstacles), O = 0 without
    obstacles: NDArray[np.float64]
    # (E, N) headings (radians), read by a model that has them (the unicycle)
    headings: NDArray[np.float64]
    # (E, N, 2) each steered point's velocity over the last step, where a model steers points
    # other than its positions (the unicycle's look-ahead points, ``Dynamics.steered``)
    steered_velocities: NDArray[np.float64]
    # (E, N) rsvo_env.geometry.clearance.contact where bodies differ or obstacles stand, else None
    contact: NDArray[np.float64] | None = None
    # (E, N) steps since each agent last came closer to its goal (the core's progress clock,
    # rsvo_env.control.stall), a copy per step; R-ORCA reads it
    # (rsvo_env.control.rorca.HOLD_SECONDS)
    no_progress: NDArray[np.int64] | None = None
    # (E, N, N) the core's weight matrices where it keeps them (sizes.WEIGHT_MATRIX_MAX_AGENTS,
    # 1,024 agents), the very arrays, for R-ORCA to read rather than compute; else None
    omega: NDArray[np.float64] | None = None

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
            steered_velocities=np.zeros((E, n, 2)),
            no_progress=np.zeros((E, n), dtype=np.int64),
        )
