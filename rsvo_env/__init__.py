"""rsvo-env: responsibility-associated multi-agent collision avoidance with social preferences.

``rsvo_env.parallel_env(scenario, **kwargs)`` makes the PettingZoo ParallelEnv (no filter; add
``wrappers.RCBFSafetyFilter``), ``rsvo_env.env(...)`` its AEC version. The standalone filter is
``rsvo_env.SafetyFilter`` (module ``rsvo_env.safety``).
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

__version__ = "0.1.0"


def parallel_env(scenario: str = "circular_swap", **kwargs: Any) -> RSVOParallelEnv:
    """The scenario as a PettingZoo ParallelEnv, without a safety filter."""
    return RSVOParallelEnv(scenario, **kwargs)


def env(scenario: str = "circular_swap", **kwargs: Any):
    """The AEC version, through PettingZoo's ``parallel_to_aec`` converter (actions checked when
    they are submitted)."""
    from rsvo_env.envs.parallel import aec_from_parallel

    return aec_from_parallel(parallel_env(scenario, **kwargs))


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
