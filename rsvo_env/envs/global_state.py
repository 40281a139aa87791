"""The global state a centralised critic sees (PettingZoo's ``state()`` / ``state_space``).

One flat float32 vector per env, in world coordinates, agents in ``possible_agents`` order:

* per agent, ``AGENT_FIELDS``: position (2), velocity (2), goal (2), theta (1), body radius (1),
  and the heading (1, radians in [-pi, pi]) for a model that has one (the unicycle);
* then per obstacle, when the scene has obstacles, its capsule (5): segment ends (x0, y0, x1, y1)
  and radius (a circle is a capsule whose ends coincide).

Every agent's observation is a function of this vector (and the weighting mode, which gives
omega from the thetas): ``tests/envs/test_global_state.py`` rebuilds the observations from it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import gymnasium
import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from rsvo_env.sim.core import Simulator

AGENT_FIELDS = ("x", "y", "vx", "vy", "goal_x", "goal_y", "theta", "radius")


def agent_fields(sim: Simulator) -> tuple[str, ...]:
    """The names of one agent's block of the state, in order."""
    return AGENT_FIELDS + tuple(name for name, _, _ in sim.scenario.model.global_fields())


def space(sim: Simulator) -> gymnasium.spaces.Box:
    """The Box every state of ``sim``'s episodes lies in: positions and goals within the
    observation's position bound, velocities within its speed bound, obstacles within the larger
    of that bound and the scene's own extent."""
    L = sim.limits
    r_max = float(np.max(sim.radii))
    lo = [-L.p, -L.p, -L.v, -L.v, -L.p, -L.p, 0.0, 0.0]
    hi = [L.p, L.p, L.v, L.v, L.p, L.p, L.theta_max, r_max]
    own = sim.scenario.model.global_fields()  # the model's columns (the unicycle's heading)
    lo, hi = lo + [low for _, low, _ in own], hi + [high for _, _, high in own]
    num_obstacles = sim.scenario.num_obstacles
    far = max(L.p, *(np.abs(a).max() for a in sim.scenario.arena()))
    rho = float(sim.scenario.max_obstacle_radius)
    low = np.array(lo * sim.n + [-far, -far, -far, -far, 0.0] * num_obstacles, dtype=np.float32)
    high = np.array(hi * sim.n + [far, far, far, far, rho] * num_obstacles, dtype=np.float32)
    return gymnasium.spaces.Box(low, high, dtype=np.float32)


def values(sim: Simulator, envs: NDArray[np.int64] | None = None) -> NDArray[np.float32]:
    """The states (E, S) float32 of ``envs`` (all by default), laid out as ``space``."""
    s = sim.state
    sel = slice(None) if envs is None else np.asarray(envs)
    pos, vel, goals = s.positions[sel], s.velocities[sel], s.goals[sel]
    E, n = pos.shape[:2]
    columns = [
        pos,
        vel,
        goals,
        s.theta[sel][..., None],
        np.broadcast_to(sim.radii, (E, n))[..., None],
    ]
    columns += [c[..., None] for c in sim.scenario.model.global_values(s, sel)]
    agents = np.concatenate(columns, axis=-1).reshape(E, -1)
    obstacles = s.obstacles[sel].reshape(E, -1)
    return np.concatenate([agents, obstacles], axis=-1).astype(np.float32)
