"""RCBFSafetyFilter: a filter stage in front of an env, for a filter of other parameters than
the env's own or a stack of filters.

Every env is filtered unless made with ``safety_filter=False`` (``rsvo_env.parallel_env``'s keywords
set its filter); this wrapper adds a stage. A thin ``BaseParallelWrapper`` that overrides nothing of
the step: it turns on a filter stage of the simulation core (``env.unwrapped.add_safety_filter``),
which filters the control about to be integrated, on the state being integrated. So the control the
filter certifies is the control applied, whatever wrappers sit between this one and the base env
(action repeat, action noise, another filter), and the infos report exactly that control
(``u_safe``) next to the requested one (``u_nominal``). Infeasible QPs apply the least-violating
action, are flagged in ``infos`` and counted in the episode metrics; the nominal is never passed
through. The wrapped env itself is filtered from then on (wrappers configure in place,
``docs/api.md``).
"""

from __future__ import annotations

from typing import Any

from pettingzoo.utils import BaseParallelWrapper

from rsvo_env.envs.factory import filter_config
from rsvo_env.filter.safety import SafetyFilter


class RCBFSafetyFilter(BaseParallelWrapper):
    """A filter stage of the paper's decentralized R-CBF filter in front of an
    ``RSVOParallelEnv`` (a bare one, ``safety_filter=False``, or one filtered already).

    Stacked filters all act, the outermost first; a filter stacked on an identical one changes
    nothing (the safe control is already feasible for the same QP).

    Args:
        env: The PettingZoo env (an ``RSVOParallelEnv`` or a wrapper of one).
        gamma: The class-K gain; None: the scenario's.
        solver: ``"exact"`` or an installed qpsolvers backend.
        intervention_penalty: ``c``: ``c |u_safe - u_nominal|^2`` (physical units) is
            subtracted from each agent's reward.
        barrier: The double integrator's barrier; None: the scenario's.
        split: How the split barriers share a pair's row; None: the scenario's.
        neighbor_radius: The pairs examined lie within it; None: every pair that can bind.

    Raises:
        ValueError: A bad value, naming the field and the value.
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
