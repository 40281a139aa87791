"""RSVOMultiAgentEnv: one filtered scenario as an RLlib ``MultiAgentEnv``.

Built from a training config (the same YAML as the SB3 path: scenario, filter, residual or direct
actions, weighting). It adapts our PettingZoo ParallelEnv directly (no SuperSuit, no RLlib
PettingZoo wrapper): agents, spaces, the global state (``state()``, ``state_space``), and
per-agent infos with the filter's signals and the
running episode's ``episode_*`` values, which ``rsvo_env.training.rllib_engine`` turns into
metrics.
"""

from __future__ import annotations

from typing import Any

import gymnasium
from ray.rllib.env.multi_agent_env import MultiAgentEnv

from rsvo_env.training.config import make_parallel


class RSVOMultiAgentEnv(MultiAgentEnv):
    """``env_config``: ``{"cfg": <resolved training config>}``; every agent has the same spaces
    and all end together (``__all__``)."""

    def __init__(self, env_config: dict[str, Any]) -> None:
        super().__init__()
        self.par_env = make_parallel(env_config["cfg"])
        self.possible_agents = list(self.par_env.possible_agents)
        self.agents = list(self.possible_agents)
        self.observation_spaces = {a: self.par_env.observation_space(a) for a in self.agents}
        self.action_spaces = {a: self.par_env.action_space(a) for a in self.agents}
        self.observation_space = gymnasium.spaces.Dict(self.observation_spaces)
        self.action_space = gymnasium.spaces.Dict(self.action_spaces)
        # the global state a centralised critic asks for (connectors reach it through the env)
        self.state_space = self.par_env.state_space

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict, dict]:
        obs, infos = self.par_env.reset(seed=seed, options=options)
        self.agents = list(self.possible_agents)
        return obs, infos

    def step(self, action_dict: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        obs, rewards, terms, truncs, infos = self.par_env.step(action_dict)
        terms["__all__"] = all(terms.values())
        truncs["__all__"] = all(truncs.values())
        if terms["__all__"] or truncs["__all__"]:
            self.agents = []
        return obs, rewards, terms, truncs, infos

    def state(self) -> Any:
        """The global state of the running episode (``rsvo_env.envs.global_state``)."""
        return self.par_env.state()

    def close(self) -> None:
        self.par_env.close()
