"""R-ORCA as a scripted controller (``docs/liveness.md``): its settings, their defaults and the
crowd's routed preset, and the step that reads the scenario's state into one call
(``scripted.steer``)."""

from __future__ import annotations

from typing import Any

from numpy.typing import NDArray

from rsvo_env.control.controllers import Controller
from rsvo_env.control.rorca import fused, route, scripted
from rsvo_env.control.rorca.scripted import RorcaSettings

# R-ORCA routed around knots, its rules set for crowds of 1,000 and 10,000 (docs/liveness.md,
# "Routing around knots"): a horizon of 1.25 s, bodies the filter's, the goal rule after 1 s
# within one radius and at once for agents that have reached their goals
ROUTED = {
    "rorca_route": True,
    "rorca_tau": 1.25,
    "rorca_pad": 1.0,
    "rorca_goal_reach": 1.0,
    "rorca_goal_hold": 1.0,
    "rorca_goal_reached": True,
}
# the general rules (the scenes' other than the crowd)
UNROUTED = RorcaSettings()._asdict()


class Rorca(Controller):
    """R-ORCA's velocity toward the preferred one (``velocities.rorca_velocities``) for the
    model's steered points (the unicycle's look-ahead points), bodies ``rorca_pad`` times
    theirs, horizon ``rorca_tau``; with ``rorca_route``, routed around knots first."""

    name = "rorca"
    settings = UNROUTED
    positive = ("rorca_tau", "rorca_pad")
    nonnegative = ("rorca_goal_reach", "rorca_goal_hold")
    reads = ("goals", "at_goal", "reached", "no_progress", "theta", "weighting", "omega")

    def check(self, params: dict[str, Any], scenario: str) -> RorcaSettings:
        super().check(params, scenario)
        return RorcaSettings(**{key: params[key] for key in UNROUTED})

    def rh_hold(self, settings: RorcaSettings) -> float:
        # routing's last resort waits: the rule turns only agents stalled this long
        return route.RH_HOLD if settings.rorca_route else 0.0

    def nominal(self, state: Any, scenario: Any, right_hand: bool) -> NDArray:
        # R-ORCA's compiled stage computes the move-to-goal velocities too, where it serves
        p = scenario.params
        points, velocities, extra = scenario.model.steered(state, p)
        turn = state.rh_active if scenario.turns(right_hand) else None
        one_call = fused.nominal(
            state,
            (state.positions, p["k"], turn, p["rh_angle_deg"]),
            points,
            velocities,
            scenario.radii + extra,
            scenario.controller_settings,
            p["safety_radius"],
            p["dt"],
            scenario.speed,
        )
        if one_call is None:
            return super().nominal(state, scenario, right_hand)
        return one_call

    def steer(self, state: Any, preferred: NDArray, scenario: Any) -> NDArray:
        points, velocities, extra = scenario.model.steered(state, scenario.params)
        return scripted.steer(state, preferred, points, velocities, scenario.radii + extra,
                              scenario.controller_settings, scenario.params["safety_radius"],
                              scenario.params["dt"], scenario.speed)  # fmt: skip
