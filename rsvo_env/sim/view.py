"""What the stages of the step (after-step, signals, reset options) read and write of the
simulator. ``rsvo_env.sim.core.Simulator`` is the one implementation; the stages take it
as a ``SimulatorView``, so that they never import the core that calls them."""

from __future__ import annotations

from typing import Protocol

from numpy.typing import NDArray

from rsvo_env.control.stall import StallClock
from rsvo_env.control.theta_action import ThetaAction
from rsvo_env.responsibility.svo import Weighting
from rsvo_env.scenarios.base import Scenario
from rsvo_env.sim.metrics import EpisodeMetrics
from rsvo_env.sim.state import State


class SimulatorView(Protocol):
    scenario: Scenario
    num_envs: int
    n: int  # agents per env
    k: int  # observed neighbours
    safety_radius: float
    max_steps: int
    reward_weights: tuple[float, float, float]  # progress, time, goal
    weighting: Weighting  # every episode's default
    theta_action: ThetaAction | None
    radii: NDArray  # (N,) body radii
    plain: bool  # identical bodies, one bound, no obstacles
    state: State
    metrics: EpisodeMetrics
    progress: StallClock  # each agent's progress clock
    deadlock_window: int  # steps without progress that make a deadlock
    post_step_in_one_call: bool
    warned_options: set[str]  # reset options already warned about, once each
