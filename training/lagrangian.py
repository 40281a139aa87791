"""PPO-Lagrangian: PPO on the shared policy under a constraint on the expected episode cost, the
constrained-RL baseline the safety filter is measured against (``docs/safe_rl.md``).

The problem is ``max_pi J_r(pi)`` subject to ``J_c(pi) <= d``: ``J_c`` the expected episode cost of
an agent (``info["cost"]``, 1.0 a step in contact, summed over its episode) and ``d`` the
``cost_limit``. Its Lagrangian ``J_r - lambda (J_c - d)`` is maximised over the policy and
minimised over ``lambda >= 0`` by dual ascent, as OmniSafe's PPO-Lag does (Ray et al., 2019):

* ``lambda <- max(0, lambda + multiplier_lr (J_c - d))`` once per update, ``J_c`` the mean cost
  of the episodes that ended during the rollout (no episode ended: no step);
* the policy's surrogate reads the advantage ``(A_r - lambda A_c) / (1 + lambda)``, ``A_r``
  standardised over the rollout and ``A_c`` centred, both by GAE; ``A_c`` from a cost critic (its
  own head of the policy, trained on the discounted cost-to-go), as a truncated episode bootstraps
  its cost from that critic as the reward does from the value.

No maintained package ships a Lagrangian PPO that runs on an SB3 ``VecEnv`` of shared-policy
slots (OmniSafe and SafePO own their envs and trainers), so this is a small subclass of SB3's PPO:
its rollouts, clipping, minibatches and logs are SB3's own.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch as th
from numpy.typing import NDArray
from stable_baselines3 import PPO
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.utils import obs_as_tensor
from torch import nn

from rsvo_env.util.validation import shown


@dataclass
class Lagrange:
    """The multiplier ``lambda`` of the cost constraint ``J_c <= cost_limit``, by dual ascent:
    ``update`` raises it while the episode cost exceeds the limit and lowers it (to 0 at the
    least) otherwise."""

    cost_limit: float
    multiplier: float = 0.5
    lr: float = 0.05

    def update(self, episode_cost: float) -> float:
        """One dual-ascent step on the mean episode cost ``J_c``; returns the new multiplier."""
        if not np.isfinite(episode_cost):
            raise ValueError(f"Lagrange.update: episode_cost = {shown(episode_cost)} is not finite")
        self.multiplier = max(0.0, self.multiplier + self.lr * (episode_cost - self.cost_limit))
        return self.multiplier


def gae(
    rewards: NDArray,
    values: NDArray,
    starts: NDArray,
    last_values: NDArray,
    last_dones: NDArray,
    gamma: float,
    lam: float,
) -> tuple[NDArray, NDArray]:
    """Generalised advantage estimates and returns (T, S) of one rollout, as SB3's buffer computes
    them for the reward: ``starts`` (T, S) marks a step that began an episode."""
    T = rewards.shape[0]
    adv = np.zeros_like(rewards)
    last = np.zeros(rewards.shape[1], dtype=rewards.dtype)
    for t in reversed(range(T)):  # a recursion in time: T is the rollout's length, ~32 to 64
        live = 1.0 - (last_dones if t == T - 1 else starts[t + 1])
        after = last_values if t == T - 1 else values[t + 1]
        delta = rewards[t] + gamma * after * live - values[t]
        last = delta + gamma * lam * live * last
        adv[t] = last
    return adv, adv + values


class CostActorCriticPolicy(ActorCriticPolicy):
    """SB3's actor-critic with a second critic, of the episode cost (the value head's layout)."""

    def _build(self, lr_schedule: Any) -> None:
        sizes = self.net_arch["vf"] if isinstance(self.net_arch, dict) else self.net_arch
        layers: list[nn.Module] = []
        width = self.features_dim
        for size in sizes:
            layers += [nn.Linear(width, size), self.activation_fn()]
            width = size
        self.cost_value_net = nn.Sequential(*layers, nn.Linear(width, 1))
        # the parent builds the optimizer over every parameter, the cost critic's included
        super()._build(lr_schedule)

    def predict_cost_values(self, obs: th.Tensor) -> th.Tensor:
        """The cost critic's estimate of the discounted cost-to-go (S, 1)."""
        features = self.extract_features(obs, self.vf_features_extractor)
        return self.cost_value_net(features)


class PPOLagrangian(PPO):
    """SB3's PPO with the cost constraint of ``Lagrange`` (module docstring). ``cost_limit``:
    the allowed mean episode cost of an agent; ``multiplier_init``, ``multiplier_lr``: the
    multiplier's start and dual step. Logged every update under ``lagrangian/``, and, with
    ``multiplier_log``, appended to that CSV (``timesteps, episode_cost, multiplier``)."""

    policy_aliases = {**PPO.policy_aliases, "MlpPolicy": CostActorCriticPolicy}

    def __init__(
        self,
        policy: Any,
        env: Any,
        cost_limit: float = 1.0,
        multiplier_init: float = 0.5,
        multiplier_lr: float = 0.05,
        multiplier_log: str | None = None,
        **kwargs: Any,
    ) -> None:
        self.lagrange = Lagrange(float(cost_limit), float(multiplier_init), float(multiplier_lr))
        self.multiplier_log = multiplier_log
        super().__init__(policy, env, **kwargs)

    def _setup_model(self) -> None:
        super()._setup_model()
        T, S = self.n_steps, self.n_envs
        self.costs, self.cost_values = np.zeros((T, S), np.float32), np.zeros((T, S), np.float32)
        self._episode_cost = np.zeros(S)  # each slot's cost so far in its episode
        self._ended_costs: list[float] = []  # episodes ended since the last update

    def _excluded_save_params(self) -> list[str]:
        # the rollout's arrays are rebuilt by _setup_model on load
        rollout = ["costs", "cost_values", "cost_advantages", "cost_returns", "_episode_cost"]
        return [*super()._excluded_save_params(), *rollout, "_ended_costs"]

    @property
    def _cost_policy(self) -> CostActorCriticPolicy:
        """The policy, as the cost critic's owner (SB3 types it as its base class)."""
        assert isinstance(self.policy, CostActorCriticPolicy)
        return self.policy

    def _cost_value(self, obs: Any) -> NDArray:
        with th.no_grad():
            tensor = obs_as_tensor(obs, self.device)
            assert isinstance(tensor, th.Tensor)  # a Box observation, not a dict
            return self._cost_policy.predict_cost_values(tensor).cpu().numpy().reshape(-1)

    def _update_info_buffer(self, infos: list[dict], dones: NDArray | None = None) -> None:
        # SB3 calls this once a step, after the env's step and before the buffer's add: the step's
        # costs go to the slot the buffer is about to fill
        super()._update_info_buffer(infos, dones)
        cost = np.array([info["cost"] for info in infos], dtype=np.float64)
        self._episode_cost += cost
        ended = np.zeros(len(infos), bool) if dones is None else np.asarray(dones, bool)
        self._ended_costs.extend(self._episode_cost[ended].tolist())
        self._episode_cost[ended] = 0.0
        for k in np.flatnonzero(ended):  # a truncated episode's cost-to-go bootstraps, as its value
            if infos[k].get("TimeLimit.truncated", False):
                terminal = infos[k]["terminal_observation"][None]
                cost[k] += self.gamma * self._cost_value(terminal)[0]
        t = self.rollout_buffer.pos
        self.costs[t] = cost
        self.cost_values[t] = self._cost_value(self._last_obs)

    def collect_rollouts(
        self, env: Any, callback: Any, rollout_buffer: Any, n_rollout_steps: int
    ) -> bool:
        if not super().collect_rollouts(env, callback, rollout_buffer, n_rollout_steps):
            return False
        assert self._last_episode_starts is not None  # set by the rollout just collected
        last = self._cost_value(self._last_obs), self._last_episode_starts.astype(np.float32)
        self.cost_advantages, self.cost_returns = gae(
            self.costs,
            self.cost_values,
            rollout_buffer.episode_starts,
            *last,
            self.gamma,
            self.gae_lambda,
        )
        return True

    def train(self) -> None:
        episode_cost = float(np.mean(self._ended_costs)) if self._ended_costs else np.nan
        if self._ended_costs:
            self.lagrange.update(episode_cost)
        self._ended_costs = []
        lam = self.lagrange.multiplier
        buf = self.rollout_buffer
        reward_adv = (buf.advantages - buf.advantages.mean()) / (buf.advantages.std() + 1e-8)
        cost_adv = self.cost_advantages - self.cost_advantages.mean()
        # the buffer's advantages are what PPO's surrogate reads: the Lagrangian's own
        buf.advantages = ((reward_adv - lam * cost_adv) / (1.0 + lam)).astype(np.float32)
        super().train()
        cost_loss = self._fit_cost_critic()
        self.logger.record("lagrangian/multiplier", lam)
        self.logger.record("lagrangian/episode_cost", episode_cost)
        self.logger.record("lagrangian/cost_limit", self.lagrange.cost_limit)
        self.logger.record("lagrangian/cost_value_loss", cost_loss)
        if self.multiplier_log is not None:
            _append_row(self.multiplier_log, self.num_timesteps, episode_cost, lam)

    def _fit_cost_critic(self) -> float:
        """The cost critic regressed on the rollout's cost-to-go, PPO's epochs and minibatches."""
        buf = self.rollout_buffer
        # PPO's pass over the buffer (its get) has flattened the arrays in place, slot by slot
        flat = buf.observations if buf.generator_ready else buf.swap_and_flatten(buf.observations)
        obs = th.as_tensor(flat, device=self.device)
        # the buffer flattens slot by slot (its swap_and_flatten): the targets in the same order
        target = th.as_tensor(self.cost_returns.swapaxes(0, 1).reshape(-1), device=self.device)
        n = len(target)
        losses = []
        for _ in range(self.n_epochs):
            for batch in th.randperm(n, device=self.device).split(self.batch_size):
                loss = nn.functional.mse_loss(
                    self._cost_policy.predict_cost_values(obs[batch]).flatten(), target[batch]
                )
                self.policy.optimizer.zero_grad()  # the other parameters keep no gradient:
                loss.backward()  # Adam leaves them as they are
                th.nn.utils.clip_grad_norm_(self.policy.parameters(), self.max_grad_norm)
                self.policy.optimizer.step()
                losses.append(loss.item())
        return float(np.mean(losses))


def _append_row(path: str, timesteps: int, episode_cost: float, multiplier: float) -> None:
    new = not Path(path).exists()
    with open(path, "a") as f:
        if new:
            f.write("timesteps,episode_cost,multiplier\n")
        f.write(f"{int(timesteps)},{shown(episode_cost)},{shown(multiplier)}\n")
