"""The scenarios' scripted R-ORCA: the state's rules read into one call of R-ORCA
(``rsvo_env.control.rorca``), after the routing around knots where it is on
(``rsvo_env.control.rorca_route``)."""

from __future__ import annotations

from typing import Any

from numpy.typing import NDArray

from rsvo_env.control import rorca, rorca_route, stall


def steer(
    state: Any,
    preferred: NDArray,
    points: NDArray,
    velocities: NDArray,
    radii: NDArray,
    params: dict[str, Any],
    speed: float,
) -> NDArray:
    """R-ORCA's velocities (E, N, 2) closest to the ``preferred`` ones for the steered
    ``points`` moving at ``velocities``, bodies ``radii`` (before ``rorca_pad``), the speed
    limit ``speed``; the scenario's ``params`` give the horizon, the pad, the goal rule's reach
    and hold (and whether agents that have reached their goals count as held), and whether the
    preferred velocities are routed around knots first."""
    p = params
    if p["rorca_route"]:
        preferred = rorca_route.routed(
            points, velocities, state.goals, state.at_goal, preferred, p["safety_radius"], speed
        )
    clock = lambda seconds: stall.held(state.no_progress, p["dt"], seconds)  # noqa: E731
    goal_held = clock(p["rorca_goal_hold"])  # None: no clock, every agent counts as held
    if p["rorca_goal_reached"] and goal_held is not None:
        # an agent that has reached its goal yields as parked within the rule's reach at once:
        # its clock restarts at every return to the goal, so a yield cycle shorter than the
        # hold never fires the rule (crowd of 1,000 at dt 0.1, seed 1008: 0.9 s, liveness.md)
        goal_held = goal_held | state.reached
    return rorca.rorca_velocities(
        points,
        velocities,
        preferred,
        p["rorca_pad"] * radii,
        state.theta,
        state.weighting,
        speed,
        p["dt"],
        p["rorca_tau"],
        rules=rorca.Rules(
            parked=state.at_goal,
            goals=state.goals,
            held=clock(rorca.HOLD_SECONDS),
            omega=state.omega,
            reach=p["rorca_goal_reach"],
            goal_held=goal_held,
        ),
    )
