"""The ids, in gymnasium's registry (JointControlEnv) and PettingZoo's (the filtered ParallelEnv).

Entry points are strings (docs/api.md): the core names the wrappers here and nowhere
else, and they are imported only when ``make`` is called. PettingZoo has a registry from 1.27 on;
with 1.24 to 1.26 (still pinned by some clients, e.g. AgileRL) the PettingZoo ids are not
registered and ``rsvo_env.parallel_env`` / ``rsvo_env.env`` make the same envs.
"""

from __future__ import annotations

import gymnasium
import pettingzoo

from rsvo_env.scenarios import SCENARIOS

OLDEST_PETTINGZOO = (1, 24)


def check_pettingzoo(version: str) -> None:
    """Refuse a PettingZoo older than 1.24 at import, naming both versions (older ones lack the
    ``ParallelEnv`` API this package implements)."""
    parts = []
    for piece in version.split(".")[:2]:
        digits = "".join(c for c in piece if c.isdigit())
        parts.append(int(digits) if digits else 0)
    if tuple(parts) < OLDEST_PETTINGZOO:
        raise ImportError(
            f"rsvo_env needs pettingzoo >= 1.24, found pettingzoo {version}: "
            "pip install 'pettingzoo>=1.24'"
        )


check_pettingzoo(pettingzoo.__version__)
# PettingZoo 1.27 added its registry (``pettingzoo.register``, ``pettingzoo.make``)
HAS_REGISTRY = hasattr(pettingzoo, "parallel_registry")

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
        kwargs = {"id_scenario": scenario}  # the id's own: ``scenario=`` may not change it
        if env_id not in gymnasium.registry:
            gymnasium.register(
                id=env_id,
                entry_point="rsvo_env.wrappers.registered:joint_env",
                vector_entry_point="rsvo_env.wrappers.registered:joint_vector_env",
                kwargs=kwargs,
                max_episode_steps=SCENARIOS[scenario].defaults["max_steps"],
            )
        if not HAS_REGISTRY:
            continue
        for env_type, registry, factory in (
            ("parallel", pettingzoo.parallel_registry, "parallel_env"),
            ("aec", pettingzoo.aec_registry, "aec_env"),
        ):
            if env_id not in registry:
                pettingzoo.register(
                    env_type, env_id, f"rsvo_env.wrappers.registered:{factory}", kwargs=dict(kwargs)
                )


register_all()
