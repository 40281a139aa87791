"""One filtered env run under its scripted controller until every agent has arrived."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np


def run_to_goals(env: Any, steps: int, before_step: Callable[[Any], None] | None = None):
    """Step ``env`` (one env, safety radius 1) under its scripted controller until every agent
    has reached its goal, an episode ends, or ``steps`` steps, asserting that no pair is ever
    closer than ``1 - 1e-9``; ``before_step(env)`` runs before each step. The agents that
    reached their goals."""
    reached = np.zeros(env.num_agents, dtype=bool)
    for _ in range(steps):
        if before_step is not None:
            before_step(env)
        _, _, term, trunc, info = env.step(env.nominal_actions())
        assert info["min_distance"].min() >= 1.0 - 1e-9
        reached |= info["at_goal"][0]
        if reached.all() or term.any() or trunc.any():
            break
    return reached
