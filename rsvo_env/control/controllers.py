"""The scripted-controller interface (``docs/architecture.md``): what a scenario asks of the
controller its ``nominal`` names. A new controller is one module with a subclass of
``Controller`` plus one line in the registry (``rsvo_env.control``)."""

from __future__ import annotations

from typing import Any, ClassVar

from numpy.typing import NDArray

from rsvo_env.util.validation import check_positive, shown


class Controller:
    """A scripted controller: from the move-to-goal velocities a scenario prefers (turned by
    the right-hand rule where it fires), the velocity each agent asks, which the scenario turns
    into the model's inputs. Stateless: one instance serves every scenario.

    ``settings``: its settings' defaults, each a scenario keyword it owns (the scenario keeps
    their values in its ``params`` and the controller's record of them in
    ``Scenario.controller_settings``); ``positive`` and ``nonnegative`` name those that must be
    > 0 and >= 0. ``reads``: the fields of the core's state ``steer`` reads.
    """

    name: ClassVar[str] = ""
    settings: ClassVar[dict[str, Any]] = {}
    positive: ClassVar[tuple[str, ...]] = ()
    nonnegative: ClassVar[tuple[str, ...]] = ()
    reads: ClassVar[tuple[str, ...]] = ()

    def check(self, params: dict[str, Any], scenario: str) -> Any:
        """Check its settings in the scenario's ``params`` (in place: numbers as floats; a bad
        one raises naming ``scenario.key``) and return its record of them."""
        for key in self.positive:
            params[key] = check_positive(params[key], f"{scenario}.{key}")
        for key in self.nonnegative:
            if params[key] < 0:
                raise ValueError(f"{scenario}.{key} = {shown(params[key])} must be >= 0")
        return None

    def rh_hold(self, settings: Any) -> float:
        """The right-hand rule's hold (s) this controller wants where the scenario's
        ``rh_hold`` is None (0: the rule turns every agent it fires for)."""
        return 0.0

    def nominal(self, state: Any, scenario: Any, right_hand: bool) -> NDArray:
        """The velocities (E, N, 2) the agents ask: ``steer`` of the ``scenario``'s
        move-to-goal velocities (turned by the right-hand rule unless ``right_hand`` is False).
        A controller whose compiled stage computes those too overrides it."""
        preferred = scenario.move_to_goal(state, right_hand, scenario.speed)
        return self.steer(state, preferred, scenario)

    def steer(self, state: Any, preferred: NDArray, scenario: Any) -> NDArray:
        """The velocities (E, N, 2) the agents ask from the ``preferred`` ones, for the
        ``scenario`` (its model's steered points, bodies, speed and ``controller_settings``)."""
        return preferred

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


class MoveToGoal(Controller):
    """The paper's move-to-goal controller (Sec. V-A): the preferred velocity itself."""

    name = "move_to_goal"
