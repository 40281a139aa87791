"""The AEC form of the parallel env, its actions checked when they are submitted."""

from __future__ import annotations

from typing import Any

from pettingzoo.utils import BaseWrapper

from rsvo_env.util.validation import check_action


class CheckedActionsAEC(BaseWrapper):
    """The AEC form of an env (``parallel_to_aec``) that refuses a bad action when it is
    submitted: PettingZoo's converter only stores it and steps the parallel env once every agent
    has acted, so a NaN would surface at another agent's turn, and every turn after it."""

    def step(self, action: Any) -> None:
        """Submit the acting agent's action, checked now.

        Args:
            action: The agent's action (None for an agent that is done).

        Raises:
            ValueError: A malformed action, naming the agent and the value.
        """
        agent = self.agent_selection
        if action is not None and not (self.terminations[agent] or self.truncations[agent]):
            check_action(action, agent, self.action_space(agent).shape)
        super().step(action)


def aec_from_parallel(parallel: Any) -> CheckedActionsAEC:
    """``parallel_to_aec`` with the actions checked on submission."""
    from pettingzoo.utils.conversions import parallel_to_aec

    return CheckedActionsAEC(parallel_to_aec(parallel))
