"""Scripted controllers by name: the registry (``docs/architecture.md``). A scenario's
``nominal`` names one; a new controller is one module with a subclass of ``Controller``
plus one line below (or a call of ``register``)."""

from __future__ import annotations

from typing import Any

from rsvo_env.control.controllers import Controller, MoveToGoal
from rsvo_env.control.rorca.controller import Rorca
from rsvo_env.util.validation import shown

CONTROLLERS: dict[str, Controller] = {}

__all__ = ["CONTROLLERS", "Controller", "get", "names", "register", "settings"]


def register(controller: Controller) -> Controller:
    """Add ``controller`` (an instance of a ``Controller`` subclass) under its ``name``; a
    name taken by another controller, or a setting another controller owns, raises."""
    if not isinstance(controller, Controller) or not controller.name:
        raise TypeError(f"register takes a Controller with a name, got {shown(controller)}")
    if CONTROLLERS.get(controller.name, controller) is not controller:
        raise ValueError(f"controller {shown(controller.name)} is registered already")
    for other in CONTROLLERS.values():
        taken = set(other.settings) & set(controller.settings)
        if other is not controller and taken:
            raise ValueError(f"settings {sorted(taken)} are the {other.name} controller's")
    CONTROLLERS[controller.name] = controller
    return controller


def names() -> tuple[str, ...]:
    """The registered controllers' names."""
    return tuple(CONTROLLERS)


def get(controller: str, field: str = "nominal") -> Controller:
    """The controller of a name; an unknown name raises naming ``field`` and the names known."""
    if isinstance(controller, str) and controller in CONTROLLERS:
        return CONTROLLERS[controller]
    raise ValueError(f"{field} = {shown(controller)}; use one of {names()}")


def settings() -> dict[str, Any]:
    """Every registered controller's settings with their defaults: the scenario keywords the
    controllers own."""
    return {key: value for c in CONTROLLERS.values() for key, value in c.settings.items()}


for _controller in (MoveToGoal(), Rorca()):
    register(_controller)
