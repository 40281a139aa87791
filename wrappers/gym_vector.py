"""GymnasiumVectorEnv: a ``BatchedEnv`` as a ``gymnasium.vector.VectorEnv``, one slot per agent.

The batched env has an agent axis a ``VectorEnv`` does not (rewards are ``(num_envs,)`` there), so,
as ``rsvo_env.wrappers.sb3.SB3VecEnv`` does, every agent of every env is a slot: E x N slots,
slot ``e * N + i`` is agent i of env e, each with one agent's observation and action spaces
(parameter sharing). All agents of an env end together. The autoreset mode is the batched env's,
declared in ``metadata["autoreset_mode"]``: ``NEXT_STEP`` (the default here, and what Gymnasium's
``NormalizeObservation`` asks for) or ``SAME_STEP`` (``final_obs`` and ``_final_obs`` per slot in
the infos). So Gymnasium's vector wrappers (``RecordEpisodeStatistics``, ``NormalizeObservation``,
``ClipAction``, ...) apply unchanged.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.util.validation import shown

MODES = {"same_step": AutoresetMode.SAME_STEP, "next_step": AutoresetMode.NEXT_STEP}


class OverBatched(VectorEnv):
    """A ``gymnasium.vector.VectorEnv`` over a ``BatchedEnv`` (``self.env``): the vector env is
    its own unwrapped env, and closing it closes the batch."""

    env: BatchedEnv

    @property
    def unwrapped(self) -> OverBatched:
        return self

    def close_extras(self, **kwargs: Any) -> None:
        self.env.close()


class GymnasiumVectorEnv(OverBatched):
    """A ``BatchedEnv`` as a Gymnasium ``VectorEnv`` of single agents: E envs of N agents are
    E N slots, each one agent (the ids' ``vector_entry_point``).

    Infos hold, per slot, every per-agent signal and its env's ``episode_*`` values, each with
    the ``_key`` mask Gymnasium's vector infos carry (all True: every slot has every key).

    Args:
        env: A ``BatchedEnv``, or a scenario's name for a new one.
        **kwargs: For a new ``BatchedEnv`` (made with ``autoreset_mode="next_step"`` unless
            given).

    Raises:
        TypeError: Keywords with a given ``BatchedEnv``.
    """

    def __init__(self, env: BatchedEnv | str = "crowd", **kwargs: Any) -> None:
        if not isinstance(env, BatchedEnv):
            kwargs.setdefault("autoreset_mode", "next_step")
            env = BatchedEnv(env, **kwargs)
        elif kwargs:
            raise TypeError(f"keywords {sorted(kwargs)} are for a new BatchedEnv, not a given one")
        self.env = env
        self.agents_per_env = env.num_agents
        self.num_envs = env.num_envs * env.num_agents
        self.metadata = {"autoreset_mode": MODES[env.autoreset_mode], "render_modes": []}
        self.render_mode = None
        self.single_observation_space = env.single_observation_space
        self.single_action_space = env.single_action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        """Reset every env.

        Args:
            seed: Env e is seeded with ``seed + e`` (the slots of an env share its seed).
            options: ``theta`` and ``weighting``.

        Returns:
            The slots' observations (E N, D) and their infos.

        Raises:
            ValueError: A list of seeds (one int or None is taken).
        """
        if isinstance(seed, (list, tuple)):
            raise ValueError(
                f"seed = {shown(seed)}: give one int (env e is seeded with seed + e) or None; the "
                "slots of an env share its seed"
            )
        obs, info = self.env.reset(seed=seed, options=options)
        return self._flat(obs), self._infos(info)

    def step(
        self, actions: Any
    ) -> tuple[NDArray, NDArray, NDArray[np.bool_], NDArray[np.bool_], dict[str, Any]]:
        """Advance every env one step.

        Args:
            actions: (E N, 2), one slot's action a row.

        Returns:
            Observations, rewards, terminated and truncated (each per slot) and the infos.

        Raises:
            ValueError: Actions of the wrong shape.
        """
        a = np.asarray(actions)
        if a.shape != self.action_space.shape:
            raise ValueError(f"actions has shape {a.shape}, expected {self.action_space.shape}")
        E, N = self.env.num_envs, self.agents_per_env
        obs, reward, terminated, truncated, info = self.env.step(a.reshape(E, N, -1))
        return (
            self._flat(obs),
            reward.reshape(-1),
            np.repeat(terminated, N),
            np.repeat(truncated, N),
            self._infos(info),
        )

    def _flat(self, obs: NDArray[np.float32]) -> NDArray[np.float32]:
        return obs.reshape(self.num_envs, -1)

    def _infos(self, info: dict[str, NDArray]) -> dict[str, Any]:
        """Per-slot arrays: (E, N, ...) signals flattened, (E,) episode values repeated per agent,
        ``final_obs`` (SAME_STEP) per slot with its ``_final_obs`` mask."""
        E, N = self.env.num_envs, self.agents_per_env
        out: dict[str, Any] = {}
        for key, value in info.items():
            if key == "_final_obs":
                continue
            if key == "final_obs":
                out[key] = value.reshape(self.num_envs, -1)
                out["_final_obs"] = np.repeat(info["_final_obs"], N)
                continue
            v = np.asarray(value)
            per_agent = v.shape[:2] == (E, N)
            out[key] = v.reshape(E * N, *v.shape[2:]) if per_agent else np.repeat(v, N, axis=0)
            out[f"_{key}"] = np.ones(self.num_envs, dtype=bool)
        return out


__all__ = ["GymnasiumVectorEnv"]
