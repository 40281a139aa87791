"""PettingZoo and Gymnasium wrappers around the rsvo_env core."""

from wrappers.joint import JointControlEnv
from wrappers.safety_filter import RCBFSafetyFilter, filtered_aec_env, filtered_parallel_env
from wrappers.weighting import ResponsibilityWeighting

__all__ = [
    "JointControlEnv",
    "RCBFSafetyFilter",
    "ResponsibilityWeighting",
    "filtered_aec_env",
    "filtered_parallel_env",
]
