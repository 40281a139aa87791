"""RCBFSafetyFilter: every action goes through the responsibility-weighted QP.

A thin ``BaseParallelWrapper`` that overrides nothing of the step: it turns on the filter stage
of the simulation core (``env.unwrapped.add_safety_filter``), which filters the control about to
be integrated, on the state being integrated. So the control the filter certifies is the control
applied, whatever wrappers sit between this one and the base env (action repeat, action noise,
another filter), and the infos report exactly that control (``u_safe``) next to the requested one
(``u_nominal``). Infeasible QPs apply the least-violating action, are flagged in ``infos`` and
counted in the episode metrics; the nominal is never passed through. The wrapped env itself
is filtered from then on (wrappers configure in place, ``docs/api.md``).
"""

from __future__ import annotations

from typing import Any

from pettingzoo.utils import BaseParallelWrapper

import rsvo_env
from rsvo_env.envs.factory import filter_config, route
from rsvo_env.filter.safety import SafetyFilter
from rsvo_env.util.validation import check_flag


class RCBFSafetyFilter(BaseParallelWrapper):
    """The paper's decentralized R-CBF filter in front of an ``RSVOParallelEnv``.

    ``gamma``, ``barrier`` and ``split`` default to the scenario's values; ``solver`` is
    ``"exact"`` or any qpsolvers name. ``intervention_penalty`` c subtracts
    ``c |u_safe - u_nominal|^2`` (physical units) from each agent's reward. Stacked filters all
    act, the outermost first; a filter stacked on an identical one changes nothing (the safe
    control is already feasible for the same QP).
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
        # Validated now, so a bad gamma or solver fails at construction, not at the first step.
        self.config = filter_config(base.scenario, gamma, solver, barrier, split, neighbor_radius)
        self.safety_filter = SafetyFilter(self.config)
        self.intervention_penalty = intervention_penalty
        base.add_safety_filter(self.safety_filter, intervention_penalty)


def filtered_parallel_env(
    scenario: str = "circular_swap", safety_filter: bool = True, **kwargs: Any
):
    """The registry's ParallelEnv: the scenario behind the filter (``safety_filter=False``: the
    bare env). The filter's keywords (``gamma``, ``solver``, ``barrier``, ``split``,
    ``neighbor_radius``, ``intervention_penalty``) go to the filter, the rest to the env, by
    the same table as ``BatchedEnv``'s (``rsvo_env.envs.factory.route``)."""
    safety_filter = check_flag(safety_filter, "safety_filter")
    filter_kwargs = route(safety_filter, kwargs)
    env = rsvo_env.parallel_env(scenario, **kwargs)
    return RCBFSafetyFilter(env, **filter_kwargs) if safety_filter else env


def filtered_aec_env(**kwargs: Any):
    """The AEC version of :func:`filtered_parallel_env` (actions checked when submitted)."""
    from rsvo_env.envs.parallel import aec_from_parallel

    return aec_from_parallel(filtered_parallel_env(**kwargs))
