"""One episode of a scenario under its scripted controller, behind the filter or not: what
``rsvo simulate`` prints and draws, and what the paper's studies run."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

import rsvo_env
from rsvo_env.envs.rendering import save_gif
from rsvo_env.util.arguments import user_input


def run(
    scenario: str = "circular_swap",
    safety_filter: bool = True,
    weighting: str = "asymmetric",
    theta: list[float] | None = None,
    seed: int = 0,
    gif: str | Path | None = None,
    gif_every: int = 5,
    render_size: int = 400,
    **kwargs: Any,
) -> dict[str, Any]:
    """One episode under the scripted nominal controller; returns the episode metrics plus the
    trajectory (T+1, N, 2), theta and goals."""
    with user_input():  # what the library refuses here is the caller's value
        env = rsvo_env.parallel_env(
            scenario,
            render_mode="rgb_array" if gif else None,
            weighting=weighting,
            render_size=render_size,
            keep_history=True,
            record_series=True,
            safety_filter=safety_filter,
            **kwargs,
        )
        options = {"theta": theta} if theta is not None else None
        env.reset(seed=seed, options=options)
    base = env.unwrapped
    frames = [env.render()] if gif else []
    while env.agents:
        env.step(base.nominal_actions())
        if gif and (base.metrics.steps % gif_every == 0 or not env.agents):
            frames.append(env.render())
    out = dict(base.episode_metrics)
    out["trajectory"] = np.stack(base.history)
    out["theta"] = base.world.theta.copy()
    out["goals"] = base.world.goals.copy()
    out["obstacles"] = base.world.obstacles.copy()
    out["safety_radius"] = base.world.safety_radius
    out["weighting"], out["filtered"] = weighting, bool(safety_filter)
    if gif:
        fps = max(1, int(round(1.0 / (base.dt * gif_every))))
        out["gif"] = save_gif([f for f in frames if f is not None], gif, fps=min(fps, 50))
    env.close()
    return out
