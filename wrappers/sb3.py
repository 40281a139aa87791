"""SB3VecEnv: a Stable-Baselines3 ``VecEnv`` over a ``BatchedEnv`` (or one ParallelEnv), one slot
per agent.

Parameter sharing: every agent of every env is a slot (E x N of them, slot ``e * N + i`` is
agent i of env e), all with the same spaces, stepped by one call of the batched core. All agents
of an env end together; the env is reset on the same step and each of its slots gets
``terminal_observation`` and ``TimeLimit.truncated`` (True only on truncation) in its info, as
SB3's ``VecEnv`` contract asks. No SuperSuit.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray
from stable_baselines3.common.vec_env.base_vec_env import VecEnv

from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.util.validation import shown
from rsvo_env.wrappers.parallel_batch import ParallelBatch

# Per-slot signals copied into every info (the filter's work and the collision cost).
SLOT_SIGNALS = ("intervention", "cost", "feasible")


class SB3VecEnv(VecEnv):
    """Stable-Baselines3's ``VecEnv`` over our envs: each agent a slot, so one shared policy
    acts for every agent (parameter sharing).

    Args:
        venv: A ``BatchedEnv`` (made with ``autoreset_mode="same_step"``, the default), whose
            ``num_envs * num_agents`` agents are the slots, or one PettingZoo ParallelEnv of
            ours (N slots).

    Raises:
        ValueError: A ``BatchedEnv`` that resets on the next step (SB3 reads the last
            observation of an episode from the step that ends it).
    """

    def __init__(self, venv: Any) -> None:
        if not isinstance(venv, BatchedEnv):
            venv = ParallelBatch(venv)
        elif venv.autoreset_mode != "same_step":
            # SB3 resets an env on the step it ends and reads its last observation from
            # ``terminal_observation``; a next-step env has ended one step before it says so
            raise ValueError(
                f"SB3VecEnv: the BatchedEnv's autoreset_mode = {shown(venv.autoreset_mode)}; SB3 "
                "resets an env on the step it ends (terminal_observation): make it with "
                "autoreset_mode='same_step' (the default)"
            )
        self.venv = venv
        self.render_mode = None
        self.agents_per_env = venv.num_agents
        super().__init__(
            venv.num_envs * venv.num_agents, venv.single_observation_space, venv.single_action_space
        )
        self._seed: int | None = None
        self._actions: NDArray[np.float64] | None = None

    # ---- the VecEnv contract ----------------------------------------------------------------
    def seed(self, seed: int | None = None) -> Sequence[int | None]:
        """Seed the next reset (what ``PPO(..., seed=s)`` calls): env e with ``seed + e``, through
        the env's own generators, never numpy's global one.

        Args:
            seed: The first env's seed; None: unseeded.

        Returns:
            Each slot's seed (the slots of an env share it).
        """
        self._seed = seed
        n = self.agents_per_env
        self._seeds = [None if seed is None else seed + k // n for k in range(self.num_envs)]
        return self._seeds

    def reset(self) -> NDArray[np.float32]:
        """Reset every env (seeded by ``seed`` once); ``reset_infos`` holds the infos.

        Returns:
            The slots' observations (E N, D).
        """
        obs, info = self.venv.reset(seed=self._seed, options=self._options[0] or None)
        self._seed = None
        self.reset_infos = self._infos(info, np.zeros(self.venv.num_envs, dtype=bool))
        return obs.reshape(self.num_envs, -1)

    def step_async(self, actions: NDArray) -> None:
        """Keep the slots' actions for ``step_wait``.

        Args:
            actions: (E N, 2), one slot's action a row.
        """
        self._actions = np.asarray(actions).reshape(
            self.venv.num_envs, self.agents_per_env, *(self.action_space.shape or ())
        )

    def step_wait(self) -> tuple[NDArray, NDArray, NDArray, list[dict]]:
        """Step every env with the kept actions; an env that ends is reset on the same step.

        Returns:
            Observations, rewards (float32) and dones per slot, and one info dict a slot (its
            filter signals; its env's ``episode_*`` values, ``terminal_observation`` and
            ``TimeLimit.truncated`` where the episode ended).
        """
        obs, reward, terminated, truncated, info = self.venv.step(self._actions)
        n = self.agents_per_env
        dones = np.repeat(terminated | truncated, n)
        infos = self._infos(info, info["_final_obs"])
        if dones.any():
            final = info["final_obs"].reshape(self.num_envs, -1)
            cut = np.repeat(truncated & ~terminated, n)
            for k in np.flatnonzero(dones):
                infos[k]["terminal_observation"] = final[k]
                infos[k]["TimeLimit.truncated"] = bool(cut[k])
        return obs.reshape(self.num_envs, -1), reward.reshape(-1).astype(np.float32), dones, infos

    def _infos(self, info: dict[str, NDArray], ended: NDArray[np.bool_]) -> list[dict[str, Any]]:
        """One dict a slot: its filter signals, and its env's episode values when it ended."""
        columns = [info[key].reshape(-1).tolist() for key in SLOT_SIGNALS]
        infos = [dict(zip(SLOT_SIGNALS, vals, strict=True)) for vals in zip(*columns, strict=True)]
        if ended.any():
            n = self.agents_per_env
            episode = {k: v for k, v in info.items() if k.startswith("episode_")}
            for e in np.flatnonzero(ended):
                values = {k: v[e].item() for k, v in episode.items()}
                for k in range(e * n, (e + 1) * n):
                    infos[k].update(values)
        return infos

    def close(self) -> None:
        """Close the env."""
        self.venv.close()

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        """The batched env's attribute, once per selected slot (they share one env).

        Args:
            attr_name: The attribute's name.
            indices: The slots (an int, a list, or None: all).

        Returns:
            The value, once per slot.
        """
        return [getattr(self.venv, attr_name)] * len(self._indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        """Set the batched env's attribute (shared by every slot).

        Args:
            attr_name: The attribute's name.
            value: Its new value.
            indices: Accepted for SB3's contract; the slots share one env.
        """
        setattr(self.venv, attr_name, value)

    def env_method(self, method_name: str, *args: Any, indices: Any = None, **kwargs: Any) -> list:
        """Call the batched env's method once.

        Args:
            method_name: The method's name.
            *args: Its arguments.
            indices: The slots the result is repeated for (None: all).
            **kwargs: Its keyword arguments.

        Returns:
            The result, once per slot.
        """
        result = getattr(self.venv, method_name)(*args, **kwargs)
        return [result] * len(self._indices(indices))

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        """Whether the slots' env is wrapped by ``wrapper_class``: never (it is ours).

        Args:
            wrapper_class: A Gymnasium wrapper class.
            indices: The slots (None: all).

        Returns:
            False, once per slot.
        """
        return [False] * len(self._indices(indices))

    def _indices(self, indices: Any) -> Sequence[int]:
        if indices is None:
            return range(self.num_envs)
        if isinstance(indices, int):
            return [indices]
        return list(indices)
