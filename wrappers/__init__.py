"""PettingZoo and Gymnasium wrappers around the rsvo_env core."""

from rsvo_env.util.validation import shown
from wrappers.gym_vector import GymnasiumVectorEnv
from wrappers.joint import JointControlEnv
from wrappers.joint_vector import JointVectorEnv
from wrappers.residual import ResidualAction
from wrappers.safety_filter import RCBFSafetyFilter, filtered_aec_env, filtered_parallel_env
from wrappers.weighting import ResponsibilityWeighting

__all__ = [
    "GymnasiumVectorEnv",
    "JointControlEnv",
    "JointVectorEnv",
    "RCBFSafetyFilter",
    "ResidualAction",
    "ResponsibilityWeighting",
    "filtered_aec_env",
    "filtered_parallel_env",
]


def __getattr__(name: str):
    # SB3VecEnv needs stable-baselines3 (the train and dev extras): imported on first use only
    if name == "SB3VecEnv":
        from wrappers.sb3 import SB3VecEnv

        return SB3VecEnv
    raise AttributeError(f"module 'wrappers' has no attribute {shown(name)}")
