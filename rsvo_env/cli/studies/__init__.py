"""The paper's studies (Sec. V), one module each: they compute and return plain data; the report
(``rsvo_env.cli.report``) and the figures (``rsvo_env.cli.figures``) are made apart."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rsvo_env.scenarios import COMMON_DEFAULTS, SCENARIOS

# The paper's own numbers, for comparison (circular game: onset / resolved / completed steps).
PAPER: dict[str, Any] = {
    "sym": (140, 390, 620),
    "asym": (142, 275, 415),
    "resolution_gain": 0.468,
    "completion_gain": 0.33,
}
# The paper's asymmetric circular example.
ALTERNATING = [2.0, 1.0, 2.0, 1.0, 2.0, 1.0]


def defaults(scenario: str) -> dict[str, Any]:
    """A scenario's default parameters, as the env uses them."""
    return {**COMMON_DEFAULTS, **SCENARIOS[scenario].defaults}


@dataclass
class Plan:
    """What a run covers: the full study or the quick one."""

    quick: bool
    seed: int

    @property
    def n_random_sets(self) -> tuple[int, int]:
        return (5, 5) if self.quick else (5, 50)

    @property
    def ramp_angles(self) -> tuple[float, ...]:
        return (20.0,) if self.quick else (15.0, 20.0, 30.0)

    @property
    def ramp_gammas(self) -> tuple[float, ...]:
        return (1.0,) if self.quick else (0.5, 1.0, 2.0)

    @property
    def total_runs(self) -> int:
        ramp = 3 * 2 * len(self.ramp_angles) * len(self.ramp_gammas) * 3
        return 6 + ramp + 3 + max(self.n_random_sets)
