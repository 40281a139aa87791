"""Fixed personality assignments measured: the scripted controller behind the R-CBF filter, every
assignment on every seed in one batched env.

The objective of the personality search (``rsvo_env.training.theta_search``) and the fixed rows
of ``benchmarks/studies/personalities.py``. Steps, not seconds: the paper reports its circular game
in steps of 0.01 s.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rsvo_env.envs.vector import BatchedEnv

# the paper's circular game (Sec. V-C): its scripted controller, not the scenario's R-ORCA
PAPER_GAME = {"nominal": "move_to_goal"}
FIELDS = ("completed", "resolution", "success", "collision_steps", "infeasible", "min_distance")


def alternating(n: int) -> list[float]:
    """The paper's assignment: theta 2, 1, 2, 1, ... around the circle."""
    return [2.0 - (i % 2) for i in range(n)]


def evaluate(
    theta: ArrayLike | None,
    seeds: Sequence[int],
    scenario: str = "circular_swap",
    weighting: str = "asymmetric",
    **kwargs: Any,
) -> dict[str, NDArray]:
    """Every assignment of ``theta`` (S, N) on every seed (None: the scenario's own, S = 1):
    arrays (S, len(seeds)) of the step all agents are first at their goals (``completed``, -1 if
    never), the deadlock's resolution time (``resolution``: steps from its onset to its
    resolution, NaN without one: where the right-hand rule first fired only after every agent
    had passed its midpoint, as routed R-ORCA's held rule does, no deadlock was resolved),
    ``success``, ``collision_steps``, ``infeasible`` agent-steps
    and ``min_distance``. ``kwargs``: the env's keywords (scenario parameters, ``max_steps``,
    the filter's)."""
    th = None if theta is None else np.atleast_2d(np.asarray(theta, dtype=np.float64))
    S, K = 1 if th is None else th.shape[0], len(seeds)
    env = BatchedEnv(
        scenario, num_envs=S * K, weighting=weighting, autoreset_mode="next_step", **kwargs
    )
    options = None if th is None else {"theta": np.repeat(th, K, axis=0)}
    env.reset(seed=[int(s) for s in seeds] * S, options=options)
    metrics = env.sim.metrics
    out = {k: np.full(S * K, np.nan) for k in FIELDS}
    done = np.zeros(S * K, dtype=bool)
    while not done.all():
        _, _, terminated, truncated, info = env.step(env.nominal_actions())
        ended = (terminated | truncated) & ~done
        if ended.any():
            for key in ("completed", "success", "collision_steps", "infeasible", "min_distance"):
                out[key][ended] = info[f"episode_{key}"][ended]
            onset, resolved = metrics.deadlock_onset[ended], metrics.deadlock_resolved[ended]
            out["resolution"][ended] = np.where(
                (onset >= 0) & (resolved >= onset), resolved - onset, np.nan
            )
            done |= ended
    return {k: v.reshape(S, K) for k, v in out.items()}


def objective(stats: dict[str, NDArray], cap: int) -> NDArray[np.float64]:
    """Mean completion step of each assignment (S,) over its seeds; an episode that never
    completes counts as twice the cap, so the search prefers finishing to anything else."""
    completed = np.where(stats["completed"] >= 0, stats["completed"], 2.0 * cap)
    return completed.mean(axis=1)
