"""A crowd of differential-drive robots (``docs/unicycle.md``): ``crowd`` with
``dynamics="unicycle"`` as its default; actions are (v, w) scaled to ``u_max`` (the forward speed
limit) and ``w_max``, in the robot's own frame."""

from __future__ import annotations

from rsvo_env.scenarios.crowd import Crowd


class UnicycleCrowd(Crowd):
    """``crowd`` with unicycles: the scripted controller steers each look-ahead point (R-ORCA
    with bodies enlarged by the look-ahead, or move-to-goal at ``-k (p - goal)`` so the axle,
    not the point, comes to rest at the goal) and maps it back to (v, w)
    (``Unicycle.track``)."""

    name = "unicycle_crowd"
    dynamics = "unicycle"
    models = ()  # the crowd of unicycles; ``crowd`` takes any model
