"""Dynamics models by name: the registry (``docs/dynamics.md``). A name or an instance is
accepted wherever a model is asked for; an unknown name raises naming it."""

from __future__ import annotations

from rsvo_env.dynamics.double_integrator import DoubleIntegrator, double_integrator_step
from rsvo_env.dynamics.model import Dynamics
from rsvo_env.dynamics.single_integrator import SingleIntegrator, single_integrator_step
from rsvo_env.dynamics.unicycle import Unicycle, unicycle_step
from rsvo_env.util.validation import shown

MODELS: dict[str, Dynamics] = {
    m.name: m for m in (SingleIntegrator(), DoubleIntegrator(), Unicycle())
}
NAMES = tuple(MODELS)

__all__ = [
    "MODELS",
    "NAMES",
    "DoubleIntegrator",
    "Dynamics",
    "SingleIntegrator",
    "Unicycle",
    "double_integrator_step",
    "get",
    "single_integrator_step",
    "unicycle_step",
]


def get(model: str | Dynamics, field: str = "dynamics") -> Dynamics:
    """The model of a name (``"single_integrator"``, ``"double_integrator"``, ``"unicycle"``)
    or an instance."""
    if isinstance(model, Dynamics):
        return model
    if isinstance(model, str) and model in MODELS:
        return MODELS[model]
    raise ValueError(
        f"{field} = {shown(model)} is unknown; use one of {NAMES} or a Dynamics instance"
    )
