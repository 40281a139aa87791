"""The scenarios' scripted R-ORCA: the state's rules read into one call of R-ORCA
(``rsvo_env.control.rorca.velocities``), after the routing around knots where it is on
(``rsvo_env.control.rorca.route``)."""

from __future__ import annotations

from typing import Any, NamedTuple

from numpy.typing import NDArray

from rsvo_env.control import stall
from rsvo_env.control.rorca import route, velocities
from rsvo_env.control.rorca.agent import GOAL_REACH, HOLD_SECONDS


class RorcaSettings(NamedTuple):
    """R-ORCA's settings, as the scenario keywords name them: the time horizon ``rorca_tau``
    (s), the body scale ``rorca_pad``, the goal rule (an agent held ``rorca_goal_hold`` s within
    ``rorca_goal_reach`` of its padded radii of its goal yields as if parked; a reach of 0 turns
    it off; ``rorca_goal_reached``: one that has reached its goal, at once), and
    ``rorca_route``: the preferred velocities turned around the knots ahead first
    (``route``)."""

    rorca_tau: float = 2.0
    rorca_pad: float = 1.05
    rorca_goal_reach: float = GOAL_REACH
    rorca_goal_hold: float = HOLD_SECONDS
    rorca_goal_reached: bool = False
    rorca_route: bool = False


def steer(
    state: Any,
    preferred: NDArray,
    points: NDArray,
    point_velocities: NDArray,
    radii: NDArray,
    settings: RorcaSettings,
    safety_radius: float,
    dt: float,
    speed: float,
) -> NDArray:
    """R-ORCA's velocities (E, N, 2) closest to the ``preferred`` ones for the steered
    ``points`` moving at ``point_velocities``, bodies ``radii`` (before ``rorca_pad``), the
    speed limit ``speed``, the step ``dt``; ``settings`` give the horizon, the pad, the goal
    rule's reach and hold (and whether agents that have reached their goals count as held), and
    whether the preferred velocities are routed around knots first (at the scale of
    ``safety_radius``)."""
    s = settings
    if s.rorca_route:
        preferred = route.routed(
            points, point_velocities, state.goals, state.at_goal, preferred, safety_radius, speed
        )
    clock = lambda seconds: stall.held(state.no_progress, dt, seconds)  # noqa: E731
    goal_held = clock(s.rorca_goal_hold)  # None: no clock, every agent counts as held
    if s.rorca_goal_reached and goal_held is not None:
        # an agent that has reached its goal yields as parked within the rule's reach at once:
        # its clock restarts at every return to the goal, so a yield cycle shorter than the
        # hold never fires the rule (crowd of 1,000 at dt 0.1, seed 1008: 0.9 s, liveness.md)
        goal_held = goal_held | state.reached
    return velocities.rorca_velocities(
        points,
        point_velocities,
        preferred,
        s.rorca_pad * radii,
        state.theta,
        state.weighting,
        speed,
        dt,
        s.rorca_tau,
        rules=velocities.Rules(
            parked=state.at_goal,
            goals=state.goals,
            held=clock(velocities.HOLD_SECONDS),
            omega=state.omega,
            reach=s.rorca_goal_reach,
            goal_held=goal_held,
        ),
    )
