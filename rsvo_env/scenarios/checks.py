"""Checks of a scene (starts, goals, bodies, obstacles) and of the filter it is stepped with:
each raises ``ValueError`` naming the agent, the obstacle and the values."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from rsvo_env.dynamics import Dynamics
from rsvo_env.geometry.clearance import contact
from rsvo_env.geometry.obstacles import nearest_points
from rsvo_env.util.validation import shown

if TYPE_CHECKING:
    from rsvo_env.filter.safety import SafetyFilter
    from rsvo_env.scenarios.base import Scenario


def check_scene(scenario: Scenario, starts: NDArray, goals: NDArray, capsules: NDArray) -> None:
    """Starts in the safe set (every pair at least ``r_i + r_j`` apart, every body clear of
    every obstacle; for the unicycle its look-ahead point, facing its goal, with the body
    enlarged by the look-ahead) and no goal inside an obstacle (nor within two look-aheads)."""
    radii = scenario.radii
    n = len(starts)
    points, grown = scenario.model.start_bodies(starts, goals, radii, scenario.params)
    what = "look-ahead points" if points is not starts else "starting positions"
    if n >= 2:
        ratio = contact(points[None], grown)[0]  # O(N) on a grid
        i = int(np.argmin(ratio))
        if ratio[i] < 1.0:
            d = np.linalg.norm(points - points[i], axis=1)
            others = np.where(np.arange(n) == i, np.inf, d / (grown[i] + grown))
            j = int(np.argmin(others))
            raise ValueError(
                f"{what} of agents {i} and {j} overlap: distance {shown(float(d[j]))} "
                f"< {shown(float(grown[i] + grown[j]))}, the sum of their radii (h < 0)"
            )
    if len(capsules) == 0:
        return
    expected = (scenario.num_obstacles, 5)
    if capsules.shape != expected:
        raise ValueError(
            f"{scenario.name}: obstacles have shape {capsules.shape}, expected {expected}"
        )
    reach = radii + 2.0 * scenario.body_margin  # a look-ahead point's body at the goal
    for what, at, margin in (("start", points, grown), ("goal", goals, reach)):
        c = nearest_points(at, capsules)
        gap = np.linalg.norm(at[:, None, :] - c, axis=-1) - capsules[:, 4] - margin[:, None]
        i, o = (int(k) for k in np.unravel_index(int(np.argmin(gap)), gap.shape))
        if gap[i, o] < 0:
            raise ValueError(
                f"the {what} of agent {i}, {at[i].tolist()}, is inside obstacle {o} "
                f"(its body would overlap it by {shown(float(-gap[i, o]))})"
            )


def check_scene_filter(scenario: Scenario, flt: SafetyFilter) -> None:
    """A filter for the scenario: its model, and support for the scene's bodies and obstacles."""
    model = flt.config.model
    if model != scenario.model:
        raise ValueError(
            f"filter dynamics {shown(flt.config.dynamics)} != scenario {shown(scenario.dynamics)}"
        )
    if not model.per_agent_bodies and not np.all(scenario.radii == scenario.radii[0]):
        raise ValueError(f"bodies of different radii are not available for the {model.name} yet")
    if scenario.agent_limits is not None and not (
        model.per_agent_bodies and model.per_agent_limits
    ):
        raise ValueError(f"input bounds per agent are not available for the {model.name} yet")
    # a model takes obstacles by its obstacle rows, or by rows of its own that hold them
    own = type(model).obstacle_rows, type(model).filter_rows
    if scenario.num_obstacles and own == (Dynamics.obstacle_rows, Dynamics.filter_rows):
        raise ValueError(f"obstacles are not available for the {model.name} yet")
