"""R-ORCA (``docs/liveness.md``): ORCA's reciprocal half-planes with the R-SVO weights, as a
scripted controller. ``velocities`` the public call, ``agent`` one agent's velocity in pieces
both compiled stages share, ``dense`` and ``grid`` the stages, ``route`` the routing around
knots, ``scripted`` the scenario's state read into one call, ``controller`` its settings and
registration."""

from rsvo_env.control.rorca.velocities import (
    ARRIVE,
    GOAL_REACH,
    HOLD_SECONDS,
    SIDESTEP,
    Rules,
    arrival_capped,
    goal_blocked,
    rorca_velocities,
)

__all__ = [
    "ARRIVE",
    "GOAL_REACH",
    "HOLD_SECONDS",
    "SIDESTEP",
    "Rules",
    "arrival_capped",
    "goal_blocked",
    "rorca_velocities",
]
