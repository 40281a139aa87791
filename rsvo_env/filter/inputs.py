"""The checks of ``rsvo_env.filter.safety.SafetyFilter.filter`` beyond positions and scores:
per-agent bodies and obstacles (a model's own inputs, such as headings, its model checks).
Each raises ``ValueError`` naming the field, the agent and the value."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rsvo_env.filter.config import FilterConfig
from rsvo_env.geometry.bodies import Bodies, check_per_agent
from rsvo_env.geometry.obstacles import Obstacles
from rsvo_env.responsibility.pair_weights import Floor
from rsvo_env.util.validation import shown


def check_bodies(
    cfg: FilterConfig,
    lead: tuple[int, ...],
    n: int,
    radii: ArrayLike | None,
    u_max: ArrayLike | None,
) -> Bodies | None:
    """The checked per-agent radii and limits of ``filter`` (None: the config's)."""
    if radii is None and u_max is None:
        return None
    if not cfg.model.per_agent_bodies:
        raise ValueError(
            f"radii and u_max per agent are not available for the {cfg.dynamics}: it takes "
            "one safety_radius and one box (FilterConfig)"
        )
    if u_max is not None and not cfg.model.per_agent_limits:
        raise ValueError(f"u_max per agent is not available for the {cfg.dynamics}")
    if u_max is not None and cfg.u_min is not None:
        raise ValueError(
            "u_max per agent gives each agent the box [-u_max_i, u_max_i]; it cannot be "
            f"combined with FilterConfig.u_min = {shown(cfg.u_min)}"
        )
    shape = (*lead, n)
    r = None if radii is None else check_per_agent(radii, "radii", shape)
    u = None if u_max is None else check_per_agent(u_max, "u_max", shape)
    E = lead[0] if lead else 1
    return Bodies.of(cfg, E, n, r, u)


def check_obstacles(obstacles: Obstacles | None, lead: tuple[int, ...]) -> NDArray | None:
    """The capsules of ``obstacles`` (None without), one set for every scene or one an env."""
    if obstacles is None:
        return None
    if not isinstance(obstacles, Obstacles):
        raise ValueError(
            f"obstacles = {shown(obstacles)}: pass an Obstacles (Obstacles.of(circles=, walls=, "
            "thickness=))"
        )
    caps = obstacles.capsules
    if caps.ndim == 3 and (not lead or caps.shape[0] != lead[0]):
        raise ValueError(
            f"obstacles has capsules of shape {caps.shape}: one set (O, 5) for every scene, "
            f"or one an env ({lead[0] if lead else 1}, O, 5)"
        )
    return caps


class KnownScenes(NamedTuple):
    """What a caller of ``SafetyFilter.apply`` already knows of its scenes: each scene's
    smallest weight ``omega_min`` (E,), each agent's nearest distance ``nearest`` (E, N), and
    ``floor``, ``pair_weights.weight_floor`` of the weights."""

    omega_min: NDArray[np.float64] | None = None
    nearest: NDArray[np.float64] | None = None
    floor: Floor | None = None
