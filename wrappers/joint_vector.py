"""JointVectorEnv: E joint-control envs as one ``gymnasium.vector.VectorEnv`` over the batched
core, what ``gymnasium.make_vec(id, E, vectorization_mode="vector_entry_point")`` returns.

Each slot is the env ``gymnasium.make(id)`` makes
(``rsvo_env.wrappers.joint.JointControlEnv``): the same observation and action spaces (every
agent's, concatenated in agent order), the reward summed over the agents, terminated when every
agent is at its goal, truncated at the step cap. The infos hold what the joint env's info holds, one
row per slot: every per-agent signal (E, N, ...), ``cost`` summed and ``min_distance`` the smallest
over the agents, the running episodes' ``episode_*`` values, each with its ``_key`` mask. All E envs
step as one array program (``rsvo_env.envs.vector.BatchedEnv``) instead of E Python envs one by one.
"""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.util.validation import shown
from rsvo_env.wrappers.gym_vector import MODES, OverBatched


class JointVectorEnv(OverBatched):
    """E envs of the joint (whole-team) env as one Gymnasium ``VectorEnv``: each env a slot,
    its joint action and observation, as a ``SyncVectorEnv`` of ``gymnasium.make(id)`` envs
    would give them.

    Args:
        scenario: A registered scenario's name.
        num_envs: How many envs.
        **kwargs: ``BatchedEnv``'s (every keyword of the scenario and the filter;
            ``safety_filter=False`` turns the filter off), the autoreset mode ``"next_step"``
            (Gymnasium's default) unless given.

    Raises:
        ValueError: A ``render_mode`` (a batch is not drawn), or a bad value.
    """

    def __init__(self, scenario: str = "crowd", num_envs: int = 1, **kwargs: Any) -> None:
        render_mode = kwargs.pop("render_mode", None)
        if render_mode is not None:
            raise ValueError(
                f"render_mode = {shown(render_mode)}: a batch of envs is not drawn; render one "
                "env (gymnasium.make)"
            )
        kwargs.setdefault("autoreset_mode", "next_step")
        self.env = BatchedEnv(scenario, num_envs=num_envs, **kwargs)
        N, single = self.env.num_agents, self.env.single_observation_space
        self.num_envs = self.env.num_envs
        self.metadata = {"autoreset_mode": MODES[self.env.autoreset_mode], "render_modes": []}
        self.render_mode = None
        self.single_observation_space = gymnasium.spaces.Box(
            np.tile(single.low, N), np.tile(single.high, N), dtype=np.float32
        )
        width = self.env.single_action_space.shape[0]
        self.joint_width = width * N  # one env's joint action: every agent's, in agent order
        self.single_action_space = gymnasium.spaces.Box(-1.0, 1.0, (width * N,), dtype=np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        """Reset every env.

        Args:
            seed: Env e is seeded with ``seed + e``, or ``seed[e]`` of a list.
            options: ``theta`` and ``weighting``.

        Returns:
            The joint observations (E, N D) and the infos.
        """
        obs, info = self.env.reset(seed=seed, options=options)
        return self._joint(obs), self._infos(info)

    def step(
        self, actions: Any
    ) -> tuple[NDArray, NDArray, NDArray[np.bool_], NDArray[np.bool_], dict[str, Any]]:
        """Advance every env one step.

        Args:
            actions: (E, A N), one joint action an env.

        Returns:
            Observations, the teams' rewards, terminated and truncated (each per env) and the
            infos.

        Raises:
            ValueError: Actions of the wrong shape.
        """
        a = np.asarray(actions)
        if a.shape != self.action_space.shape:
            raise ValueError(
                f"actions has shape {a.shape}, expected {self.action_space.shape} (one joint "
                f"action of {self.joint_width} values for each of "
                f"{self.num_envs} envs)"
            )
        E, N = self.num_envs, self.env.num_agents
        obs, reward, terminated, truncated, info = self.env.step(a.reshape(E, N, -1))
        return self._joint(obs), reward.sum(axis=1), terminated, truncated, self._infos(info)

    def _joint(self, obs: NDArray[np.float32]) -> NDArray[np.float32]:
        return obs.reshape(self.num_envs, -1)

    def _infos(self, info: dict[str, NDArray]) -> dict[str, Any]:
        """The joint env's info a row per slot, each key with its ``_key`` mask; ``final_obs``
        (same-step mode) joint, with the batched env's ``_final_obs`` mask."""
        out: dict[str, Any] = {}
        every = np.ones(self.num_envs, dtype=bool)
        for key, value in info.items():
            if key == "_final_obs":
                continue
            if key == "final_obs":
                out[key], out["_final_obs"] = self._joint(value), info["_final_obs"]
                continue
            if key == "cost":
                value = value.sum(axis=1)
            elif key == "min_distance":
                value = value.min(axis=1)
            out[key], out[f"_{key}"] = value, every
        return out

    def nominal_action(self) -> NDArray[np.float32]:
        """The scripted controller's joint actions (E, A N)."""
        return self._joint(self.env.nominal_actions())


__all__ = ["JointVectorEnv"]
