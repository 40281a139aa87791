"""PettingZoo and Gymnasium wrappers around the rsvo_env core (installed as
``rsvo_env.wrappers``)."""

from rsvo_env.util.validation import shown
from rsvo_env.wrappers.gym_vector import GymnasiumVectorEnv
from rsvo_env.wrappers.joint import JointControlEnv
from rsvo_env.wrappers.joint_vector import JointVectorEnv
from rsvo_env.wrappers.residual import ResidualAction
from rsvo_env.wrappers.safety_filter import RCBFSafetyFilter
from rsvo_env.wrappers.weighting import ResponsibilityWeighting

__all__ = [
    "GymnasiumVectorEnv",
    "JointControlEnv",
    "JointVectorEnv",
    "RCBFSafetyFilter",
    "ResidualAction",
    "ResponsibilityWeighting",
]


def __getattr__(name: str):
    # SB3VecEnv needs stable-baselines3 (the train and dev extras): imported on first use only
    if name == "SB3VecEnv":
        from rsvo_env.wrappers.sb3 import SB3VecEnv

        return SB3VecEnv
    raise AttributeError(f"module 'rsvo_env.wrappers' has no attribute {shown(name)}")
