"""rsvo-env: responsibility-associated multi-agent collision avoidance with social preferences."""

from __future__ import annotations

from rsvo_env.responsibility import r_svo, responsibility_weight, weight_matrix
from rsvo_env.safety import FilterConfig, FilterResult, SafetyFilter

__version__ = "0.1.0"

__all__ = [
    "FilterConfig",
    "FilterResult",
    "SafetyFilter",
    "r_svo",
    "responsibility_weight",
    "weight_matrix",
]
