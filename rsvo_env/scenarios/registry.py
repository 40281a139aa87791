"""Every scenario by name: ``SCENARIOS`` and ``make_scenario``."""

from __future__ import annotations

from typing import Any

from rsvo_env.scenarios.base import Scenario
from rsvo_env.scenarios.crowd import Crowd
from rsvo_env.scenarios.paper import CircularSwap, PositionSwap, RampMerge
from rsvo_env.scenarios.scenes import Doorway, ObstacleField, Scene
from rsvo_env.scenarios.unicycle_crowd import UnicycleCrowd
from rsvo_env.util.validation import shown

SCENARIOS: dict[str, type[Scenario]] = {
    cls.name: cls
    for cls in (
        PositionSwap,
        CircularSwap,
        RampMerge,
        Crowd,
        Scene,
        Doorway,
        ObstacleField,
        UnicycleCrowd,
    )
}


def make_scenario(scenario: str | Scenario, **kwargs: Any) -> Scenario:
    """A scenario by name.

    Args:
        scenario: ``position_swap``, ``circular_swap``, ``ramp_merge``, ``crowd``, ``custom``,
            ``doorway``, ``obstacle_field``, ``unicycle_crowd`` (``SCENARIOS``), or a
            ``Scenario``, returned as it is.
        **kwargs: The scenario's parameters (its page lists each, with its default).

    Returns:
        The scenario.

    Raises:
        TypeError: An unknown keyword, or keywords with a ``Scenario`` given.
        ValueError: An unknown name, or a bad value (naming the parameter and the value).
    """
    if isinstance(scenario, Scenario):
        if kwargs:
            raise TypeError("keyword arguments go to the scenario's constructor, not here")
        return scenario
    if scenario not in SCENARIOS:
        raise ValueError(f"unknown scenario {shown(scenario)}; use one of {sorted(SCENARIOS)}")
    return SCENARIOS[scenario](**kwargs)
