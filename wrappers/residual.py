"""ResidualAction: an agent's action is a correction added to the scripted nominal command.

The learner outputs a residual; the env adds it to the scripted move-to-goal command (with or
without the right-hand rule), gates it off within ``gate_radius`` of the agent's goal (where the
scripted controller already holds the agent inside the goal tolerance) unless, with
``yield_radius``, a neighbour still en route is that close, and holds the sum to the
speed limit like every other command. With ``interaction_radius``, an agent en route with no
other agent that close follows the scripted command alone. The safety filter, when on, filters
the sum. A thin ``BaseParallelWrapper``: it switches the core's residual mode and overrides
nothing, so the wrapped env itself takes residual actions from then on (wrappers configure in
place, ``docs/api.md``).

With it, the scripted controller is the zero action; ``nominal_actions()`` still gives the
scripted command itself (for a direct-action env), not a residual.
"""

from __future__ import annotations

from typing import Any

from pettingzoo.utils import BaseParallelWrapper

from rsvo_env.control.residual import Residual


class ResidualAction(BaseParallelWrapper):
    """Residual actions: each agent's action is added to the scripted nominal command (the
    scenario's controller), for every model, within each agent's own limit.

    Args:
        env: The PettingZoo env (an ``RSVOParallelEnv`` or a wrapper of one).
        gate_radius: Distance to the goal (physical units) under which the residual is ignored.
        residual_right_hand: Whether the scripted command includes the right-hand rule.
        residual_scale: The residual's largest norm in speed limits (2 lets it reverse a
            full-speed command, 1 only turn it).
        yield_radius: With it, a parked agent's residual acts again while a neighbour still en
            route is closer than this (physical units), so it may step aside.
        interaction_radius: With it, the residual of an agent en route acts only while another
            agent is closer than this.
        stall_gate: With it, the residual of an agent that has come no closer to its goal for
            this many seconds is ignored until it does again.

    Raises:
        ValueError: A bad value, naming the field and the value.
    """

    def __init__(
        self,
        env: Any,
        gate_radius: float = Residual.gate_radius,
        residual_right_hand: bool = Residual.right_hand,
        residual_scale: float = Residual.scale,
        yield_radius: float | None = Residual.yield_radius,
        interaction_radius: float | None = Residual.interaction_radius,
        stall_gate: float | None = Residual.stall_gate,
    ) -> None:
        super().__init__(env)
        radii = (yield_radius, interaction_radius)
        env.unwrapped.set_residual(
            Residual(gate_radius, residual_right_hand, residual_scale, *radii, stall_gate)
        )
        # the keywords' names, as BatchedEnv and the training configs spell them
        self.gate_radius = gate_radius
        self.residual_right_hand, self.residual_scale = residual_right_hand, residual_scale
        self.yield_radius, self.interaction_radius = radii
        self.stall_gate = stall_gate
