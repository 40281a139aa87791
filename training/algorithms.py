"""The SB3 algorithm class each config ``algo`` names (imported only when asked for)."""

from __future__ import annotations

from typing import Any


def algorithm_class(algo: str) -> Any:
    """``ppo`` and ``sac``: Stable-Baselines3's; ``ppo_lagrangian``: ``PPOLagrangian``."""
    if algo == "ppo_lagrangian":
        from rsvo_env.training.lagrangian import PPOLagrangian

        return PPOLagrangian
    from stable_baselines3 import PPO, SAC

    return {"ppo": PPO, "sac": SAC}[algo]
