"""JointControlEnv: all agents as one ``gymnasium.Env`` (one Box action, one Box observation).

This is what ``gymnasium.make("rsvo/CircularSwap-v0")`` returns: the filtered ParallelEnv seen
by a single controller. Reward: the sum over agents; terminated when all agents are at their
goals; truncated at ``max_steps``. The info is flat (no nested dicts, no ``episode`` key, which
Gymnasium's ``RecordEpisodeStatistics`` and SB3's ``Monitor`` reserve): ``cost`` (summed),
``min_distance`` (smallest), every per-agent signal stacked in agent order (``u_safe`` (N, 2),
``feasible`` (N,), ...), and the running episode's ``episode_*`` values.
"""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np

import rsvo_env
from rsvo_env.util.validation import shown


class JointControlEnv(gymnasium.Env):
    """The whole team as one Gymnasium ``Env`` (the ids ``rsvo/<Scenario>-v0``): one joint
    action, one observation, the team's reward.

    Action: ``Box(-1, 1, (A N,))``, agent i's action at ``[A i, A i + A)`` (A = 2, or 3 with
    ``theta_action=True``). Observation: the agents' observations concatenated in
    ``possible_agents`` order. ``parallel`` is the PettingZoo ParallelEnv it drives.

    Args:
        scenario: A registered scenario's name.
        safety_filter: Every action through the R-CBF filter; False: the bare env.
        render_mode: ``"human"``, ``"rgb_array"`` or None.
        **kwargs: Every keyword of [RSVOParallelEnv][rsvo_env.RSVOParallelEnv].
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 50}

    def __init__(
        self,
        scenario: str = "circular_swap",
        safety_filter: bool = True,
        render_mode: str | None = None,
        **kwargs: Any,
    ) -> None:
        self.parallel = rsvo_env.parallel_env(
            scenario, safety_filter=safety_filter, render_mode=render_mode, **kwargs
        )
        base = self.parallel.unwrapped
        self.base = base
        self.render_mode = render_mode
        self.agent_names = list(base.possible_agents)
        n = len(self.agent_names)
        obs_spaces = [base.observation_space(a) for a in self.agent_names]
        self.observation_space = gymnasium.spaces.Box(
            np.concatenate([s.low for s in obs_spaces]),
            np.concatenate([s.high for s in obs_spaces]),
            dtype=np.float32,
        )
        self.width = base.action_space(self.agent_names[0]).shape[0]
        self.action_space = gymnasium.spaces.Box(-1.0, 1.0, (self.width * n,), dtype=np.float32)

    def _flat(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        return np.concatenate([obs[a] for a in self.agent_names]).astype(np.float32)

    def reset(
        self, *, seed: int | None = None, options: dict | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start an episode.

        Args:
            seed: Seeds the env's generators; None: an episode seed drawn from Gymnasium's own
                seeded generator.
            options: ``theta`` and ``weighting`` for this episode.

        Returns:
            The joint observation and the info (each per-agent signal as an array in agent
            order, ``cost`` summed, ``min_distance`` the least).
        """
        super().reset(seed=seed)
        if seed is None and not hasattr(self, "_seeded"):
            # draw the episode seeds from gymnasium's own seeded generator, never a global one
            seed = int(self.np_random.integers(2**31))
        self._seeded = True
        obs, infos = self.parallel.reset(seed=seed, options=options)
        return self._flat(obs), self._info(infos)

    def _info(self, infos: dict[str, dict[str, Any]]) -> dict[str, Any]:
        per_agent = [infos[a] for a in self.agent_names]
        first = per_agent[0]
        info: dict[str, Any] = {
            key: (
                first[key] if key.startswith("episode_") else np.array([i[key] for i in per_agent])
            )
            for key in first
        }
        info["cost"] = float(info["cost"].sum())
        info["min_distance"] = float(info["min_distance"].min())
        return info

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Advance every agent one step.

        Args:
            action: The joint action (A N,).

        Returns:
            The joint observation, the team's reward (the agents' sum), terminated (every agent
            done), truncated and the info.

        Raises:
            ValueError: A joint action of the wrong shape, or an agent's action not finite
                (naming the agent).
        """
        a = np.asarray(action, dtype=np.float64)
        if a.shape != self.action_space.shape:
            raise ValueError(
                f"action has shape {a.shape}, expected {self.action_space.shape} "
                f"({self.width} values for each of {len(self.agent_names)} agents)"
            )
        per_agent = a.reshape(-1, self.width)
        bad = ~np.isfinite(per_agent).all(axis=1)
        if bad.any():
            i = int(np.argmax(bad))
            raise ValueError(
                f"action of agent {shown(self.agent_names[i])} (index {i}) = "
                f"{per_agent[i].tolist()} is not finite"
            )
        actions = {name: per_agent[i] for i, name in enumerate(self.agent_names)}
        obs, rewards, terms, truncs, infos = self.parallel.step(actions)
        reward = float(sum(rewards.values()))
        terminated = all(terms.values())
        truncated = (not terminated) and any(truncs.values())
        return self._flat(obs), reward, terminated, truncated, self._info(infos)

    def nominal_action(self) -> np.ndarray:
        """The scripted controller's joint action for the current state."""
        nominal = self.base.nominal_actions()
        return np.concatenate([nominal[a] for a in self.agent_names]).astype(np.float32)

    def render(self):
        """Draw the current step (an RGB frame in ``"rgb_array"`` mode, else None)."""
        return self.parallel.render()

    def close(self) -> None:
        """Close the renderer's window, if any."""
        self.parallel.close()
