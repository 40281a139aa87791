"""The scenarios: the paper's experiments, the crowd, scenes with bodies and obstacles, the
unicycle crowd, and the registry that makes them by name (``docs/scenarios.md``)."""

from rsvo_env.scenarios.base import COMMON_DEFAULTS, DEADLOCK_RESOLUTIONS, Scenario
from rsvo_env.scenarios.crowd import Crowd
from rsvo_env.scenarios.paper import CircularSwap, PositionSwap, RampMerge, paired_theta
from rsvo_env.scenarios.registry import SCENARIOS, make_scenario
from rsvo_env.scenarios.scenes import Doorway, ObstacleField, Scene
from rsvo_env.scenarios.unicycle_crowd import UnicycleCrowd

__all__ = [
    "COMMON_DEFAULTS",
    "DEADLOCK_RESOLUTIONS",
    "SCENARIOS",
    "CircularSwap",
    "Crowd",
    "Doorway",
    "ObstacleField",
    "PositionSwap",
    "RampMerge",
    "Scenario",
    "Scene",
    "UnicycleCrowd",
    "make_scenario",
    "paired_theta",
]
