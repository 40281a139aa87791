"""BatchedEnv: E envs x N agents of one scenario as arrays, the batched adapter over the core.

One ``rsvo_env.sim.core.Simulator`` steps every env in one array program, the safety filter a
stage of its step. Env e of ``reset(seed=s)`` is seeded with ``s + e`` and equals, bit for bit,
an ``RSVOParallelEnv`` reset with seed ``s + e`` (and reset without a seed after each episode).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium
import numpy as np
from numpy.typing import NDArray

from rsvo_env.control.residual import Residual
from rsvo_env.envs import global_state
from rsvo_env.envs.factory import make_simulator
from rsvo_env.responsibility.svo import Weighting
from rsvo_env.scenarios import Scenario
from rsvo_env.util.validation import check_seed, check_vectors, shown

AUTORESET_MODES = ("same_step", "next_step")


def _rows(mask: NDArray[np.bool_], like: NDArray) -> NDArray[np.bool_]:
    """The env mask (E,) shaped to broadcast over an array (E, ...)."""
    return mask.reshape(mask.shape + (1,) * (like.ndim - 1))


class BatchedEnv:
    """``num_envs`` copies of a scenario, stepped together, with per-env auto-reset.

    ``reset(seed, options) -> (obs (E, N, D) float32, info)``;
    ``step(actions (E, N, 2)) -> (obs, reward (E, N), terminated (E,), truncated (E,), info)``.
    Actions are normalised as in the ParallelEnv (norm clipped to 1, scaled by the speed
    limit); with ``theta_action=True`` they are (E, N, 3), the last component each agent's
    theta for the step (``rsvo_env.control.theta_action``). ``info`` is a dict of arrays, the
    same
    keys at every step (with theta actions, ``theta`` (E, N) too):

    * every per-agent signal, (E, N, ...): ``u_nominal``, ``u_safe``, ``intervention``,
      ``feasible``, ``active_constraints``, ``max_violation``, ``min_distance``, ``cost``,
      ``at_goal``, ``rh_active``, ``deadlocked``;
    * the running episode's ``episode_steps``, ``episode_success``, ``episode_completed``,
      ``episode_min_distance``, ``episode_collision_steps``, ``episode_infeasible``,
      ``episode_arrived``, ``episode_makespan``, (E,);
    * ``_final_obs`` (E,): the envs whose episode ended at this step. Those envs are reset on
      the same step: ``obs`` holds their new episode's first observation, ``final_obs`` their
      last one (rows of other envs are not meaningful), and the signals and ``episode_*``
      values of this step are still those of the episode that ended.

    ``autoreset_mode="next_step"`` (Gymnasium's ``AutoresetMode.NEXT_STEP``) resets an ended
    env at the following ``step`` instead: that step ignores the env's actions and returns its
    new episode's first observation, reward 0, not terminated, not truncated, and the signals
    and ``episode_*`` values of the new episode; ``obs`` of the ending step is the last one, and
    there is no ``final_obs``. An env's episodes are the same in both modes.

    Reset options (``theta``, (N,) or (E, N), and ``weighting``) hold for the auto-resets that
    follow, until the next ``reset``.

    Args:
        scenario: A registered scenario's name or a ``Scenario``.
        num_envs: How many envs (E), >= 1.
        safety_filter: Every action through the R-CBF filter; False: the bare envs.
        action: ``"direct"`` (the action is the command) or ``"residual"`` (added to the
            scripted nominal command).
        gate_radius: Residual mode: within this distance of its goal an agent is parked, and
            its residual acts only to yield (>= 0).
        residual_right_hand: Residual mode: the scripted command under the residual includes
            the right-hand rule.
        residual_scale: Residual mode: the residual's largest norm in speed limits (> 0; 1 lets
            it turn a full-speed command by up to 90 degrees, 2 also reverse it).
        yield_radius: Residual mode: a parked agent's residual acts while another agent is
            closer than this; None: never.
        interaction_radius: Residual mode: an en-route agent's residual acts only while another
            agent is closer than this; None: always.
        stall_gate: Residual mode: the residual of an agent that has come no closer to its goal
            for this long (s) is ignored until it does again; None: never ignored.
        autoreset_mode: ``"same_step"`` or ``"next_step"`` (above).
        **kwargs: Every keyword of [RSVOParallelEnv][rsvo_env.RSVOParallelEnv] (the filter's
            ``gamma``, ``solver``, ``intervention_penalty``, ``barrier``, ``split``,
            ``neighbor_radius``; ``num_obs_neighbors``, ``frame``, ``weighting``,
            ``reward_*``, ``max_cycles``, ``theta_action``) and of the scenario.

    Raises:
        TypeError: An unknown keyword.
        ValueError: A bad value, naming the field and the value.
    """

    render_mode = None  # a batch is not drawn; one env is (``RSVOParallelEnv``)

    def __init__(
        self,
        scenario: str | Scenario = "crowd",
        num_envs: int = 1,
        safety_filter: bool = True,
        action: str = "direct",
        gate_radius: float = Residual.gate_radius,
        residual_right_hand: bool = Residual.right_hand,
        residual_scale: float = Residual.scale,
        yield_radius: float | None = Residual.yield_radius,
        interaction_radius: float | None = Residual.interaction_radius,
        stall_gate: float | None = Residual.stall_gate,
        autoreset_mode: str = "same_step",
        **kwargs: Any,
    ) -> None:
        if action not in ("direct", "residual"):
            raise ValueError(f"action = {shown(action)}; use 'direct' or 'residual'")
        if autoreset_mode not in AUTORESET_MODES:
            raise ValueError(
                f"autoreset_mode = {shown(autoreset_mode)}; use one of {AUTORESET_MODES}"
            )
        self.autoreset_mode = autoreset_mode
        # checked whatever the action mode: a bad value is refused, not ignored
        residual = Residual(
            gate_radius,
            residual_right_hand,
            residual_scale,
            yield_radius,
            interaction_radius,
            stall_gate,
        )
        self.sim = make_simulator(
            scenario, num_envs=num_envs, safety_filter=safety_filter, **kwargs
        )
        self.scenario = self.sim.scenario
        if action == "residual":
            self.sim.set_residual(residual)
        self.num_envs, self.num_agents = self.sim.num_envs, self.sim.n
        self.single_observation_space, self.single_action_space = self.sim.spaces()
        low, high = self.single_observation_space.low, self.single_observation_space.high
        E, N = self.num_envs, self.num_agents
        self.observation_space = gymnasium.spaces.Box(
            np.broadcast_to(low, (E, N, len(low))),
            np.broadcast_to(high, (E, N, len(high))),
            dtype=np.float32,
        )
        A = self.sim.action_width
        self.action_space = gymnasium.spaces.Box(-1.0, 1.0, (E, N, A), dtype=np.float32)
        self.single_state_space = global_state.space(self.sim)
        S = self.single_state_space
        self.state_space = gymnasium.spaces.Box(
            np.broadcast_to(S.low, (E, *S.shape)),
            np.broadcast_to(S.high, (E, *S.shape)),
            dtype=np.float32,
        )
        self._reset_args: tuple[NDArray | None, Weighting | None] | None = None
        # next_step mode: the envs that ended at the last step, reset at this one
        self._pending = np.zeros(E, dtype=bool)

    def reset(
        self,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[NDArray[np.float32], dict[str, NDArray]]:
        """Reset every env.

        Args:
            seed: Env e is seeded with ``seed + e`` (all unseeded: None), or, as Gymnasium's
                vector envs take it, with ``seed[e]`` of a list of one seed (or None) an env.
            options: ``theta`` ((N,) or (E, N)) and ``weighting``, held for the auto-resets
                that follow until the next ``reset``.

        Returns:
            The observations (E, N, D) float32 and the info dict of arrays.

        Raises:
            ValueError: Bad seeds or options, naming the field and the value; the envs are
                left as they were.
        """
        if isinstance(seed, (list, tuple)):
            if len(seed) != self.num_envs:
                raise ValueError(f"seed has {len(seed)} entries, expected {self.num_envs}")
            seeds = [check_seed(s, f"seed[{e}]") for e, s in enumerate(seed)]
        else:
            first = check_seed(seed)
            seeds = [None if first is None else first + e for e in range(self.num_envs)]
        theta, weighting = self.sim.check_options(options)
        self.sim.reset(range(self.num_envs), seeds, theta, weighting)
        self._reset_args = (theta, weighting)
        self._pending[:] = False
        obs = self.sim.observe()
        return obs, self._info(self.sim.signals(), obs, np.zeros(self.num_envs, dtype=bool))

    def step(
        self, actions: Any
    ) -> tuple[NDArray[np.float32], NDArray, NDArray[np.bool_], NDArray[np.bool_], dict]:
        """Advance every env one step; an env whose episode ends is reset (``autoreset_mode``).

        Args:
            actions: (E, N, 2) in ``[-1, 1]`` per component ((E, N, 3) with theta actions).

        Returns:
            Observations (E, N, D), rewards (E, N), terminated (E,), truncated (E,) and the
            info dict of arrays.

        Raises:
            ValueError: Malformed actions, naming the env, the agent and the value.
            RuntimeError: Before ``reset``.
        """
        if self._reset_args is None:
            raise RuntimeError("call reset() before step()")
        a = check_vectors(
            actions, "actions", self.num_agents, lead=(self.num_envs,), width=self.sim.action_width
        )
        obs, reward, terminated, truncated, signals = self.sim.step(a)
        if self.autoreset_mode == "next_step":
            return self._next_step(obs, reward, terminated, truncated, signals)
        done = terminated | truncated
        # the ended envs' last observations, kept before their new episode overwrites them
        final_obs = obs.copy() if done.any() else obs
        info = self._info(signals, final_obs, done)
        if done.any():
            envs = np.flatnonzero(done)
            theta, weighting = self._reset_args
            self.sim.reset(envs, [None] * len(envs), theta, weighting)
            obs[envs] = self.sim.observe(envs)
        return obs, reward, terminated, truncated, info

    def _next_step(
        self, obs: NDArray, reward: NDArray, terminated: NDArray, truncated: NDArray, signals: dict
    ) -> tuple[NDArray, NDArray, NDArray, NDArray, dict]:
        """The step's results with the envs that ended last step reset instead: the core stepped
        every env, and the rows of those envs, stepped from their last state, are replaced."""
        pending = self._pending
        if pending.any():
            envs = np.flatnonzero(pending)
            assert self._reset_args is not None  # set by reset, which every step follows
            theta, weighting = self._reset_args
            self.sim.reset(envs, [None] * len(envs), theta, weighting)
            obs[envs] = self.sim.observe(envs)
            reward[envs] = 0.0
            terminated[envs] = truncated[envs] = False
            fresh = self.sim.signals()
            signals = {k: np.where(_rows(pending, v), fresh[k], v) for k, v in signals.items()}
        self._pending = terminated | truncated
        return obs, reward, terminated, truncated, self._info(signals)

    def _info(
        self, signals: dict, final_obs: NDArray | None = None, done: NDArray | None = None
    ) -> dict[str, NDArray]:
        """The signals and the running episodes' values; with ``final_obs`` (same-step mode)
        the ended envs' last observations and their mask."""
        info = dict(signals)
        info.update(self.sim.metrics.flat())
        if final_obs is not None:
            info["final_obs"] = final_obs
            info["_final_obs"] = done
        return info

    def state(self) -> NDArray[np.float32]:
        """Each env's global state (E, S), as ``RSVOParallelEnv.state()`` of that env."""
        if self._reset_args is None:
            raise RuntimeError("call reset() before state()")
        return global_state.values(self.sim)

    def nominal_actions(self) -> NDArray[np.float32]:
        """The scripted controller's normalised actions (E, N, A) for the current state (with
        theta actions, the component that keeps each agent's theta)."""
        return self.sim.nominal_actions().astype(np.float32)

    def set_weighting(self, mode: Weighting) -> None:
        """Set the weighting of the running and all later episodes.

        Args:
            mode: ``"asymmetric"``, ``"symmetric"`` or a callable ``theta -> W``.
        """
        self.sim.set_weighting(None, mode)
        self.sim.weighting = mode
        if self._reset_args is not None:
            self._reset_args = (self._reset_args[0], mode)

    def close(self) -> None:
        """Nothing to release; present for the vector-env protocol."""
