"""RLlib callbacks: the filter's episode values as RLlib metrics (under ``env_runners/rsvo``)."""

from __future__ import annotations

from typing import Any

import numpy as np
from ray.rllib.callbacks.callbacks import RLlibCallback


class EpisodeMetrics(RLlibCallback):
    """At each episode's end: success, completion (steps), collision steps (the cost),
    infeasible steps and the mean intervention of the episode's last chunk, from the infos our
    env gives every agent (the ``episode_*`` values are the env's, equal for all agents)."""

    def on_episode_end(self, *, episode: Any, metrics_logger: Any = None, **kwargs: Any) -> None:
        if metrics_logger is None:
            return
        last = episode.get_infos(-1)
        info = last[sorted(last)[0]]
        log = metrics_logger.log_value
        log(("rsvo", "success"), float(info["episode_success"]), reduce="mean", window=100)
        if info["episode_completed"] >= 0:
            log(("rsvo", "completion_steps"), float(info["episode_completed"]), window=100)
        log(("rsvo", "collision_steps"), float(info["episode_collision_steps"]), window=100)
        log(("rsvo", "infeasible"), float(info["episode_infeasible"]), window=100)
        chunk = episode.get_infos()
        values = [
            i["intervention"]
            for per_agent in chunk.values()
            for i in (per_agent if isinstance(per_agent, list) else [per_agent])
        ]
        log(("rsvo", "intervention"), float(np.mean(values)) if values else 0.0, window=100)
