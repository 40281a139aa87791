"""Residual actions: a learner's action is a correction added to the scripted nominal command.

The residual (the action mapped to the model's inputs as any action is: for a planar model its
norm clipped to 1 times the agent's limit, for the unicycle (v, w) within its bounds; then times
``scale``) is added to the scenario's nominal command (with or without the right-hand rule) and
the sum is held to each agent's own bounds, like every other command; the safety filter, when
on, filters the sum. The residual is gated off within ``gate_radius`` of the agent's goal, where
the scripted controller alone brings the agent inside the goal tolerance and holds it there.

A parked agent is a fixed obstacle to the others: the filter only ever slows an agent, never
pushes one aside, so a goal behind parked agents cannot be reached. With ``yield_radius`` the
gate of an agent opens again while a neighbour still en route (farther than ``gate_radius``
from its own goal) is closer than ``yield_radius``: the policy may then step aside, and the
scripted command brings the agent back once the neighbour has gone.

A policy trained to hold still near its goal (to let a neighbour pass) tends to hold still there
with nobody around too. With ``interaction_radius`` the residual of an agent en route
acts only while another agent is closer than that: alone, an agent follows the scripted command,
which is what an agent alone should do.

A policy trained in crowds of a dozen meets jams in crowds of a hundred that it never saw, and
its residual can hold an agent in one. With ``stall_gate`` (seconds) the residual of an agent
that has come no closer to its goal for that long is ignored until it does again: the
scripted controller, which is live (``docs/liveness.md``), takes the agent on, and the policy
acts again from its next progress. The env's progress clock (``rsvo_env.control.stall``) is the one
the deadlock signal reads.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rsvo_env.control import stall
from rsvo_env.util import grid, planar
from rsvo_env.util.validation import check_flag, check_positive, check_real, shown


@dataclass(frozen=True)
class Residual:
    """The residual mode's parameters (physical units): ``gate_radius`` >= 0, ``scale`` > 0
    (1 lets a residual turn a full-speed command by up to 90 degrees, 2 also reverse it),
    ``yield_radius`` > 0 or None (no yielding), ``interaction_radius`` > 0 or None (the
    residual of an agent en route acts whatever its neighbours' distance), ``stall_gate`` > 0
    seconds or None (the residual acts however long the agent has made no progress)."""

    gate_radius: float = 0.5
    right_hand: bool = True
    scale: float = 1.0
    yield_radius: float | None = None
    interaction_radius: float | None = None
    stall_gate: float | None = None

    def __post_init__(self) -> None:
        gate = check_real(self.gate_radius, "gate_radius")
        if gate < 0:
            raise ValueError(f"gate_radius = {shown(self.gate_radius)} must be >= 0")
        object.__setattr__(self, "gate_radius", gate)
        object.__setattr__(self, "scale", check_positive(self.scale, "residual scale"))
        object.__setattr__(self, "right_hand", check_flag(self.right_hand, "right_hand"))
        for name in ("yield_radius", "interaction_radius", "stall_gate"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, check_positive(getattr(self, name), name))

    def env_keywords(self) -> dict[str, Any]:
        """These settings as the keywords of ``BatchedEnv`` (``ENV_KEYWORDS``)."""
        return {kw: getattr(self, name) for kw, name in ENV_KEYWORDS.items()}

    @classmethod
    def of_env_keywords(cls, settings: dict[str, Any]) -> Residual:
        """From ``BatchedEnv``'s spelling of the settings (a training config's too); a
        setting not given takes its default here."""
        return cls(**{name: settings[kw] for kw, name in ENV_KEYWORDS.items() if kw in settings})

    def open(self, positions: NDArray[np.float64], goals: NDArray[np.float64]) -> NDArray:
        """(E, N): whose residual acts. An agent en route (at least ``gate_radius`` from its
        goal): always, or with ``interaction_radius`` only while closer than it to another agent
        of the same env. A parked agent (within ``gate_radius``): with ``yield_radius``, while
        closer than that to a neighbour of the same env that is en route; else never."""
        en_route = planar.norm(positions - goals) >= self.gate_radius
        radii = [r for r in (self.yield_radius, self.interaction_radius) if r is not None]
        if not radii or (self.interaction_radius is None and en_route.all()):
            return en_route
        i, j = grid.pairs_within_radii(positions, np.full(en_route.shape, max(radii)))
        flat = en_route.reshape(-1)
        x = positions.reshape(-1, 2)
        d = planar.norm(x[i] - x[j])
        opened = flat.copy()
        if self.interaction_radius is not None:
            near = np.zeros_like(flat)
            close = d < self.interaction_radius
            near[i[close]] = near[j[close]] = True
            opened &= near
        if self.yield_radius is not None:
            # only a parked agent yields: an agent en route is governed by the gate above
            close = d < self.yield_radius
            opened[i[close & flat[j] & ~flat[i]]] = True
            opened[j[close & flat[i] & ~flat[j]]] = True
        return opened.reshape(en_route.shape)

    def acting(self, scenario: Any, state: Any) -> NDArray[np.bool_]:
        """(E, N): whose residual acts this step, ``open`` and, with ``stall_gate``, not
        stalled for that long."""
        on = self.open(state.positions, state.goals)
        if self.stall_gate is not None:
            stalled = stall.held(state.no_progress, scenario.params["dt"], self.stall_gate)
            if stalled is not None:
                on = on & ~stalled
        return on

    def controls(
        self,
        scenario: Any,
        state: Any,
        residual: NDArray[np.float64],
        hold: Callable[[NDArray[np.float64]], NDArray[np.float64]],
    ) -> NDArray[np.float64]:
        """The controls (E, N, 2): the scripted command plus the gated ``residual`` (the model's
        inputs, as the action maps to them), the sum held to each agent's bounds by ``hold``
        (``Dynamics.hold``)."""
        on = self.acting(scenario, state)
        nominal = scenario.nominal(state, self.right_hand)
        gated = np.where(on[..., None], self.scale * residual, 0.0)
        return hold(nominal + gated)


# BatchedEnv's (and the training configs') keyword for each setting of Residual
ENV_KEYWORDS = {
    "gate_radius": "gate_radius",
    "residual_right_hand": "right_hand",
    "residual_scale": "scale",
    "yield_radius": "yield_radius",
    "interaction_radius": "interaction_radius",
    "stall_gate": "stall_gate",
}
