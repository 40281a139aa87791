"""A crowd of differential-drive robots (``docs/unicycle.md``): the ``crowd`` layout, every agent
a unicycle that starts facing its goal; actions are (v, w) scaled to ``u_max`` (the forward
speed limit) and ``w_max``, in the robot's own frame."""

from __future__ import annotations

from rsvo_env.control import nominal
from rsvo_env.scenarios.crowd import Crowd


class UnicycleCrowd(Crowd):
    """``crowd`` with unicycles: the scripted controller drives each look-ahead point at
    ``-k (p - goal)`` (so the axle, not the point, comes to rest at the goal) and maps it back
    to (v, w) exactly."""

    name = "unicycle_crowd"
    dynamics = "unicycle"
    positive = (*Crowd.positive, "lookahead", "w_max")
    # starts R + 4 l apart: the look-ahead points, kept R + 2 l apart by the filter, start in
    # its safe set whatever the headings (|q_i - q_j| >= |p_i - p_j| - 2 l)
    defaults = {**Crowd.defaults, "lookahead": 0.2, "w_max": 3.0, "spacing_factor": 2.0,
                "side_factor": 3.5, "nominal": "move_to_goal"}  # fmt: skip

    def check(self) -> None:
        p = self.params
        need = 1.0 + 4.0 * p["lookahead"] / p["safety_radius"]
        if p["spacing_factor"] < need:
            raise ValueError(
                f"unicycle_crowd.spacing_factor = {p['spacing_factor']!r} must be at least "
                f"1 + 4 lookahead / safety_radius = {need!r}: the look-ahead points must start "
                "at least safety_radius + 2 lookahead apart"
            )
        if p["lookahead"] * p["w_max"] >= p["u_max"]:
            raise ValueError(
                f"unicycle_crowd: lookahead * w_max = {p['lookahead'] * p['w_max']!r} must be "
                f"below u_max = {p['u_max']!r} (the forward speed limit)"
            )

    def nominal(self, state, right_hand=True):
        p = self.params
        c = nominal.move_to_goal(state.positions, state.goals, p["k"], self.u_max,
                                 state.rh_active if self.turns(right_hand) else None,
                                 p["rh_angle_deg"])  # fmt: skip
        return self.model.toward(state.positions, state.headings, c, p)
