"""The ids, in gymnasium's registry (JointControlEnv) and PettingZoo's (the filtered ParallelEnv).

Entry points are strings (docs/api.md): the core names the wrappers here and nowhere
else, and they are imported only when ``make`` is called.
"""

from __future__ import annotations

import gymnasium
import pettingzoo

from rsvo_env.scenarios import SCENARIOS

IDS = {
    "rsvo/PositionSwap-v0": "position_swap",
    "rsvo/CircularSwap-v0": "circular_swap",
    "rsvo/RampMerge-v0": "ramp_merge",
    "rsvo/Crowd-v0": "crowd",
    "rsvo/Doorway-v0": "doorway",
    "rsvo/ObstacleField-v0": "obstacle_field",
    "rsvo/UnicycleCrowd-v0": "unicycle_crowd",
}


def register_all() -> None:
    for env_id, scenario in IDS.items():
        kwargs = {"scenario": scenario}
        if env_id not in gymnasium.registry:
            gymnasium.register(
                id=env_id,
                entry_point="wrappers.joint:JointControlEnv",
                kwargs=kwargs,
                max_episode_steps=SCENARIOS[scenario].defaults["max_steps"],
            )
        for env_type, registry, factory in (
            ("parallel", pettingzoo.parallel_registry, "filtered_parallel_env"),
            ("aec", pettingzoo.aec_registry, "filtered_aec_env"),
        ):
            if env_id not in registry:
                pettingzoo.register(
                    env_type, env_id, f"wrappers.safety_filter:{factory}", kwargs=dict(kwargs)
                )


register_all()
