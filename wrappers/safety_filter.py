"""RCBFSafetyFilter: every nominal action goes through the responsibility-weighted QP.

A thin ``BaseParallelWrapper`` (it overrides only ``reset`` and ``step``): it reads the world
through ``env.unwrapped``, calls :class:`rsvo_env.safety.SafetyFilter`, hands the safe controls
to the base env (``set_next_controls``) and steps the wrapped env with the nominal actions, so
that wrappers in between see the step. Infeasible QPs apply the least-violating action, are
flagged in ``infos`` and counted in the episode metrics; the nominal is never passed through.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pettingzoo.utils import BaseParallelWrapper

import rsvo_env
from rsvo_env.safety import FilterConfig, SafetyFilter
from rsvo_env.validation import check_action_dict


class RCBFSafetyFilter(BaseParallelWrapper):
    """The paper's decentralized R-CBF filter in front of an ``RSVOParallelEnv``.

    ``gamma``, ``barrier`` and ``split`` default to the scenario's values (DESIGN.md section 5);
    ``solver`` is ``"exact"`` or any qpsolvers name. ``intervention_penalty`` c subtracts
    ``c |u_safe - u_nominal|^2`` (physical units) from each agent's reward.
    """

    def __init__(
        self,
        env: Any,
        gamma: float | None = None,
        solver: str = "exact",
        intervention_penalty: float = 0.0,
        barrier: str | None = None,
        split: str | None = None,
        neighbor_radius: float | None = None,
    ) -> None:
        super().__init__(env)
        base = env.unwrapped
        sc = base.scenario
        params = sc.params
        self.intervention_penalty = float(intervention_penalty)
        if not np.isfinite(self.intervention_penalty) or self.intervention_penalty < 0:
            raise ValueError(f"intervention_penalty = {intervention_penalty!r} must be >= 0")
        # Validated now, so a bad gamma or solver fails at construction, not at the first step.
        self.config = FilterConfig(
            gamma=params["gamma"] if gamma is None else gamma,
            safety_radius=params["safety_radius"],
            u_max=sc.u_max,
            dt=params["dt"],
            dynamics=sc.dynamics,
            solver=solver,
            barrier=barrier or params.get("barrier", "braking"),
            split=split or params.get("split", "capability"),
            neighbor_radius=neighbor_radius,
        )
        self.safety_filter = SafetyFilter(self.config)
        self.last_result = None

    def reset(self, seed: int | None = None, options: dict | None = None):
        self.last_result = None
        return self.env.reset(seed=seed, options=options)

    def step(self, actions: dict[str, Any]):
        base = self.env.unwrapped
        base._require_running()
        a = check_action_dict(actions, base.agents)
        u_nominal = base.action_to_control(a)
        w = base.world
        res = self.safety_filter.filter(
            w.positions,
            u_nominal,
            w.theta,
            velocities=w.velocities if w.dynamics == "double_integrator" else None,
            omega=w.omega,
        )
        base.set_next_controls(
            res.actions,
            {
                "feasible": res.feasible,
                "n_unrecoverable_pairs": res.n_unrecoverable_pairs,
                "n_capped_shares": res.n_capped_shares,
                "min_h": res.min_h,
            },
        )
        self.last_result = res
        try:
            obs, rewards, terms, truncs, infos = self.env.step(actions)
        finally:
            # a wrapper in between that refuses the step must not leave these for a later one
            base._next_controls = None
        # One copy per field and step; each agent's entry is a row of it.
        u_nom, u_safe = u_nominal.copy(), res.actions.copy()
        interventions = res.intervention.tolist()
        feasible, active = res.feasible.tolist(), res.active.tolist()
        violation = res.max_violation.tolist()
        for i, agent in enumerate(base.possible_agents):
            if agent not in infos:
                continue
            infos[agent].update(
                u_nominal=u_nom[i],
                u_safe=u_safe[i],
                intervention=interventions[i],
                feasible=feasible[i],
                active_constraints=active[i],
                max_violation=violation[i],
            )
            if self.intervention_penalty and agent in rewards:
                rewards[agent] -= self.intervention_penalty * interventions[i] ** 2
        return obs, rewards, terms, truncs, infos


def filtered_parallel_env(
    scenario: str = "circular_swap",
    safety_filter: bool = True,
    gamma: float | None = None,
    solver: str = "exact",
    intervention_penalty: float = 0.0,
    **kwargs: Any,
):
    """The registry's ParallelEnv: the scenario behind the filter (``safety_filter=False``: the
    bare env)."""
    env = rsvo_env.parallel_env(scenario, **kwargs)
    if not safety_filter:
        if gamma is not None or solver != "exact" or intervention_penalty:
            raise TypeError("gamma, solver and intervention_penalty need safety_filter=True")
        return env
    return RCBFSafetyFilter(
        env, gamma=gamma, solver=solver, intervention_penalty=intervention_penalty
    )


def filtered_aec_env(**kwargs: Any):
    """The AEC version of :func:`filtered_parallel_env`."""
    from pettingzoo.utils.conversions import parallel_to_aec

    return parallel_to_aec(filtered_parallel_env(**kwargs))
