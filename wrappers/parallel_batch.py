"""ParallelBatch: one PettingZoo ParallelEnv of ours seen as a batch of one env (E = 1).

It gives ``rsvo_env.wrappers.sb3.SB3VecEnv`` (and anything else written against
``rsvo_env.envs.vector.BatchedEnv``) the same arrays from a single, possibly wrapped, ParallelEnv:
``(1, N, ...)`` observations, rewards and signals, ``(1,)`` episode flags, ``final_obs`` and
per-episode auto-reset. This is the single-env path the batched core is measured against.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray


class ParallelBatch:
    """``env``: an ``RSVOParallelEnv`` or any PettingZoo wrapper of one; its agents keep the
    order of ``possible_agents``. Signals are read from the per-agent infos."""

    num_envs = 1

    def __init__(self, env: Any) -> None:
        self.env = env
        self.render_mode = env.render_mode
        self.agents = list(env.possible_agents)
        self.num_agents = len(self.agents)
        self.single_observation_space = env.observation_space(self.agents[0])
        self.single_action_space = env.action_space(self.agents[0])
        self._options: dict[str, Any] | None = None

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, NDArray]]:
        self._options = options
        obs, infos = self.env.reset(seed=seed, options=options)
        return self._obs(obs), self._info(infos, self._obs(obs), False)

    def step(self, actions: Any) -> tuple[NDArray, NDArray, NDArray, NDArray, dict]:
        a = np.asarray(actions)
        want = (1, self.num_agents, *self.single_action_space.shape)
        if a.shape != want:
            raise ValueError(f"actions has shape {a.shape}, expected {want}")
        step = self.env.step(dict(zip(self.agents, a[0], strict=True)))
        obs, rewards, terms, truncs, infos = step
        first = self.agents[0]
        terminated = np.array([terms[first]])
        truncated = np.array([truncs[first]])
        reward = np.array([[rewards[a] for a in self.agents]], dtype=np.float64)
        last = self._obs(obs)
        done = bool(terminated[0] or truncated[0])
        info = self._info(infos, last, done)
        if done:
            # reset without a seed: the env's own generator continues, as the batched env does
            obs, _ = self.env.reset(options=self._options)
            last = self._obs(obs)
        return last, reward, terminated, truncated, info

    def _obs(self, obs: dict[str, NDArray]) -> NDArray[np.float32]:
        return np.stack([obs[a] for a in self.agents])[None].astype(np.float32, copy=False)

    def _info(self, infos: dict[str, dict], final_obs: NDArray, done: bool) -> dict[str, NDArray]:
        first = infos[self.agents[0]]
        info: dict[str, NDArray] = {}
        for key, value in first.items():
            if key.startswith("episode_"):
                info[key] = np.array([value])
            else:
                info[key] = np.array([[infos[a][key] for a in self.agents]])
        info["final_obs"] = final_obs
        info["_final_obs"] = np.array([done])
        return info

    def close(self) -> None:
        self.env.close()
