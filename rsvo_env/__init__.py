"""rsvo-env: responsibility-associated multi-agent collision avoidance with social preferences.

Every entry point filters every action through the R-CBF safety filter unless it is given
``safety_filter=False``: ``rsvo_env.parallel_env(scenario, **kwargs)`` (the PettingZoo
ParallelEnv), ``rsvo_env.env(...)`` (its AEC version), ``rsvo_env.BatchedEnv`` (many envs as
arrays), ``gymnasium.make("rsvo/...")`` and ``pettingzoo.make``. The filter alone, on plain
arrays, is ``rsvo_env.SafetyFilter``. The wrappers are ``rsvo_env.wrappers``, training is
``rsvo_env.training`` (the ``train`` extra).
"""

from __future__ import annotations

from typing import Any

from rsvo_env.envs import registration  # noqa: E402,F401  (registers the ids on import)
from rsvo_env.envs.parallel import RSVOParallelEnv
from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.filter.safety import FilterConfig, FilterResult, SafetyFilter
from rsvo_env.geometry.obstacles import Obstacles
from rsvo_env.responsibility.svo import r_svo, responsibility_weight, weight_matrix
from rsvo_env.scenarios import SCENARIOS, make_scenario

__version__ = "1.0.0"


def parallel_env(
    scenario: str = "circular_swap", safety_filter: bool = True, **kwargs: Any
) -> RSVOParallelEnv:
    """The scenario as a PettingZoo ParallelEnv, every action through the safety filter.

    Args:
        scenario: A registered scenario's name (``SCENARIOS``).
        safety_filter: Every action through the R-CBF filter; False: the bare env.
        **kwargs: The filter's (``gamma``, ``solver``, ``barrier``, ``split``,
            ``neighbor_radius``, ``intervention_penalty``), the env's and the scenario's
            keywords ([RSVOParallelEnv][rsvo_env.RSVOParallelEnv]).

    Returns:
        The env.
    """
    return RSVOParallelEnv(scenario, safety_filter=safety_filter, **kwargs)


def env(scenario: str = "circular_swap", safety_filter: bool = True, **kwargs: Any) -> Any:
    """The AEC version of [parallel_env][rsvo_env.parallel_env], through PettingZoo's
    ``parallel_to_aec`` converter (actions checked when they are submitted).

    Args:
        scenario: A registered scenario's name.
        safety_filter: Every action through the R-CBF filter; False: the bare env.
        **kwargs: As [parallel_env][rsvo_env.parallel_env]'s.

    Returns:
        The AEC env.
    """
    from rsvo_env.envs.aec import aec_from_parallel

    return aec_from_parallel(parallel_env(scenario, safety_filter, **kwargs))


__all__ = [
    "SCENARIOS",
    "BatchedEnv",
    "FilterConfig",
    "FilterResult",
    "Obstacles",
    "RSVOParallelEnv",
    "SafetyFilter",
    "env",
    "make_scenario",
    "parallel_env",
    "r_svo",
    "responsibility_weight",
    "weight_matrix",
]
