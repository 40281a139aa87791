"""Building the core and its filter from a scenario and keyword arguments: the one place both
adapters (``RSVOParallelEnv``, ``BatchedEnv``) and the filter wrapper take their keywords."""

from __future__ import annotations

from typing import Any

from rsvo_env.filter.safety import FilterConfig, SafetyFilter
from rsvo_env.scenarios import Scenario, make_scenario
from rsvo_env.sim.core import REWARDS, Simulator
from rsvo_env.util.validation import check_flag

SIM_KEYWORDS = (
    "num_obs_neighbors",
    "frame",
    "weighting",
    "reward_progress",
    "reward_time",
    "reward_goal",
    "stall_clock",
    "reward_team",
    "theta_action",
    "theta_action_range",
)
# The filter's keywords: every adapter takes them out of its keywords by this one table and hands
# them to the filter (FilterConfig is their owner; the scenario's gamma, barrier and split are the
# defaults a filter starts from).
FILTER_KEYWORDS = ("gamma", "solver", "barrier", "split", "neighbor_radius", "intervention_penalty")


def route(safety_filter: bool, kwargs: dict[str, Any]) -> dict[str, Any]:
    """Take the filter's keywords out of ``kwargs`` (in place) and return those given (None is
    the default); refuse them without a filter, where they would do nothing."""
    filter_kwargs = {k: kwargs.pop(k) for k in FILTER_KEYWORDS if k in kwargs}
    filter_kwargs = {k: v for k, v in filter_kwargs.items() if v is not None}
    effective = [
        k
        for k, v in filter_kwargs.items()
        if not (k == "intervention_penalty" and isinstance(v, (int, float)) and v == 0)
    ]
    if not safety_filter and effective:
        raise TypeError(f"filter parameters {sorted(effective)} need safety_filter=True")
    return filter_kwargs


def make_simulator(
    scenario: str | Scenario,
    num_envs: int = 1,
    max_cycles: int | None = None,
    record_series: bool = False,
    safety_filter: bool = True,
    **kwargs: Any,
) -> Simulator:
    """The core for a scenario (name or instance), behind the safety filter unless
    ``safety_filter=False``: the one safety default of every entry point, since both adapters
    are built through here. ``kwargs`` holds the filter's keywords (``FILTER_KEYWORDS``),
    the simulator's (``SIM_KEYWORDS``) and the scenario's parameters; ``max_cycles`` is
    PettingZoo's name for ``max_steps``."""
    safety_filter = check_flag(safety_filter, "safety_filter")
    filter_kwargs = route(safety_filter, kwargs)
    sim = _simulator(scenario, num_envs, max_cycles, record_series, kwargs)
    if safety_filter:
        penalty = filter_kwargs.pop("intervention_penalty", 0.0)
        sim.add_filter(SafetyFilter(filter_config(sim.scenario, **filter_kwargs)), penalty)
    return sim


def _simulator(
    scenario: str | Scenario,
    num_envs: int,
    max_cycles: int | None,
    record_series: bool,
    kwargs: dict[str, Any],
) -> Simulator:
    if max_cycles is not None:
        if "max_steps" in kwargs:
            raise TypeError("give max_steps or its PettingZoo name max_cycles, not both")
        kwargs["max_steps"] = max_cycles
    sim_kwargs = {k: kwargs.pop(k) for k in SIM_KEYWORDS if k in kwargs}
    rewards = {k: sim_kwargs.pop(k) for k in REWARDS if k in sim_kwargs}
    return Simulator(
        make_scenario(scenario, **kwargs),
        num_envs=num_envs,
        record_series=record_series,
        rewards=rewards,
        **sim_kwargs,
    )


def filter_config(
    scenario: Scenario,
    gamma: float | None = None,
    solver: str = "exact",
    barrier: str | None = None,
    split: str | None = None,
    neighbor_radius: float | None = None,
) -> FilterConfig:
    """The filter's parameters for a scenario: its gamma, radius, limits, dt and dynamics,
    each overridable (validated now, so a bad value fails before the first step)."""
    p = scenario.params
    return FilterConfig(
        gamma=p["gamma"] if gamma is None else gamma,
        safety_radius=p["safety_radius"],
        u_max=scenario.u_max,
        dt=p["dt"],
        dynamics=scenario.dynamics,
        solver=solver,
        # a value given is used as given (a falsy one is refused by name, never replaced)
        barrier=p.get("barrier", FilterConfig.barrier) if barrier is None else barrier,
        split=p.get("split", FilterConfig.split) if split is None else split,
        neighbor_radius=neighbor_radius,
        lookahead=p.get("lookahead"),
        w_max=p.get("w_max"),
    )
