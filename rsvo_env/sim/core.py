"""The simulation core: E envs x N agents of one scenario stepped by one array program.

``step`` takes normalised actions (E, N, 2) and runs, for all envs at once::

    actions -> controls (clip norm, scale, frame) -> [filter stage] -> integrate -> signals

The filter stage ([`SafetyFilter`][rsvo_env.SafetyFilter] s) acts right before integration on
the state being integrated: the control it certifies is the one integrated, whatever the wrappers.
Adapters (``RSVOParallelEnv``: E = 1, dicts; ``BatchedEnv``: arrays) only reshape the API. Each
env has its own seeded generator; this class is the one writer of the state.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import gymnasium
import numpy as np
from gymnasium.utils import seeding
from numpy.typing import NDArray

from rsvo_env.control.residual import Residual
from rsvo_env.control.stall import StallClock, deadlock_steps, goal_distance
from rsvo_env.control.theta_action import theta_action_of
from rsvo_env.filter.result import FilterResult, merge_stats
from rsvo_env.filter.safety import FilterConfig, KnownScenes, SafetyFilter
from rsvo_env.geometry.bodies import Bodies
from rsvo_env.responsibility.pair_weights import Floor
from rsvo_env.responsibility.svo import Weighting, check_weighting
from rsvo_env.scenarios import Scenario
from rsvo_env.scenarios.checks import check_scene, check_scene_filter
from rsvo_env.sim import observation, obstacle_observation, post_step, signals
from rsvo_env.sim.metrics import EpisodeMetrics
from rsvo_env.sim.reset_options import check_options
from rsvo_env.sim.state import State
from rsvo_env.sim.weights import Weights
from rsvo_env.util import planar, sizes
from rsvo_env.util.validation import check_count, check_real, shown

# the reward's weights (``rewards=``): progress toward the goal, the time cost, the goal bonus,
# and the share of each agent's reward replaced by its env's mean
REWARDS = {"reward_progress": 1.0, "reward_time": 0.01, "reward_goal": 10.0, "reward_team": 0.0}


class Simulator:
    """State arrays (E, N, ...), per-env generators and per-env reset, and the step above.

    ``weighting``: every episode's default (a reset option overrides it once); ``rewards``
    (``REWARDS``, each ``reward_*`` keyword) weigh the reward terms (``reward_team``: the share
    of each agent's reward replaced by its env's mean); ``stall_clock``: observe each agent's
    ``rsvo_env.control.stall.StallClock``, in units of that many steps (None: not observed);
    ``record_series`` (E = 1) keeps the series the paper plots; ``theta_action``: each action gets a
    third component, the agent's theta for the step, on ``theta_action_range``
    (``rsvo_env.control.theta_action``)."""

    def __init__(
        self,
        scenario: Scenario,
        num_envs: int = 1,
        num_obs_neighbors: int | None = None,
        frame: str = "world",
        weighting: Weighting = "asymmetric",
        rewards: dict[str, Any] | None = None,
        stall_clock: int | None = None,
        record_series: bool = False,
        theta_action: bool = False,
        theta_action_range: Any = None,
    ) -> None:
        n = scenario.num_agents
        check_count(num_envs, "num_envs", 1)
        if frame not in observation.FRAMES:
            raise ValueError(f"frame = {shown(frame)}; use one of {observation.FRAMES}")
        if num_obs_neighbors is None:
            num_obs_neighbors = min(n - 1, 6)
        if (
            isinstance(num_obs_neighbors, (bool, np.bool_))
            or not isinstance(num_obs_neighbors, (int, np.integer))
            or not 0 <= num_obs_neighbors < n
        ):
            raise ValueError(
                f"num_obs_neighbors = {shown(num_obs_neighbors)} must be in [0, {n - 1}]"
            )
        check_weighting(weighting, np.ones(n))  # now, not at the first reset
        self.scenario, self.num_envs, self.n = scenario, int(num_envs), n
        self.k = int(num_obs_neighbors)
        self.frame, self.weighting = frame, weighting
        r = {**REWARDS, **(rewards or {})}
        progress, time, goal = (
            check_real(r[name], name) for name in ("reward_progress", "reward_time", "reward_goal")
        )
        self.reward_weights = (progress, time, goal)
        self.reward_team = check_real(r["reward_team"], "reward_team")
        if not 0.0 <= self.reward_team <= 1.0:
            raise ValueError(f"reward_team = {shown(r['reward_team'])} must be in [0, 1]")
        p = scenario.params
        self.dt, self.max_steps, self.u_max = float(p["dt"]), int(p["max_steps"]), scenario.u_max
        self.safety_radius = float(p["safety_radius"])
        self.theta_action = theta_action_of(theta_action, theta_action_range, p["theta_max"])
        self.action_width = 2 if self.theta_action is None else 3
        self.world_params = {
            "safety_radius": self.safety_radius,
            "u_max": self.u_max,
            "dt": self.dt,
            "dynamics": scenario.dynamics,
            "gamma": float(p["gamma"]),
            "goal_tolerance": float(p["goal_tolerance"]),
            "barrier": p.get("barrier", FilterConfig.barrier),
            "split": p.get("split", FilterConfig.split),
        }
        self.filters: list[SafetyFilter] = []
        self.penalties: list[float] = []
        self.warned_options: set[str] = set()
        self.residual: Residual | None = None
        self.weights = Weights(self.num_envs, n)  # the one writer: set_theta, set_weighting, reset
        self.rngs: list[np.random.Generator | None] = [None] * self.num_envs
        self.radii = scenario.radii  # (N,) body radii
        self.plain = scenario.plain  # identical bodies, one bound, no obstacles: kept once
        self.state = State.empty(self.num_envs, n, self.k, scenario.num_obstacles)
        # up to sizes.WEIGHT_MATRIX_MAX_AGENTS (1,024) agents the matrices exist from the start
        # and Weights writes them in place: the state holds the very arrays, for R-ORCA to read
        self.state.omega = self.weights.matrix
        self._bodies: dict[int, Bodies | None] = {}
        self.metrics = EpisodeMetrics(
            self.num_envs, n, self.dt, self.safety_radius, record_series=record_series
        )
        self.limits = observation.limits_for(scenario)
        # every agent's progress clock (rsvo_env.control.stall): the deadlock signal, observed as
        # the stall clock when ``stall_clock`` is given
        unit = 1 if stall_clock is None else stall_clock
        self.progress = StallClock.create(unit, self.num_envs, n)
        self.stall = None if stall_clock is None else self.progress
        if self.stall is not None:
            self.limits = replace(self.limits, stall=self.stall.bound(self.max_steps))
        self.deadlock_window = deadlock_steps(self.dt)
        # the after-integration stage in one compiled call where the scenario allows it
        self.post_step_in_one_call = post_step.one_call_serves(scenario, n)

    def spaces(self) -> tuple[gymnasium.spaces.Box, gymnasium.spaces.Box]:
        """One agent's observation and action spaces (bounded Boxes, float32)."""
        low, high = observation.bounds(self.limits, self.k, self.stall is not None)
        k_o = obstacle_observation.count(self.scenario.num_obstacles)
        if k_o:
            reach = float(self.radii.max()) + self.scenario.max_obstacle_radius
            lo_o, hi_o = obstacle_observation.bounds(self.limits.p, reach, k_o)
            low, high = np.r_[low, lo_o].astype(np.float32), np.r_[high, hi_o].astype(np.float32)
        return (
            gymnasium.spaces.Box(low, high, dtype=np.float32),
            gymnasium.spaces.Box(-1.0, 1.0, (self.action_width,), dtype=np.float32),
        )

    def add_filter(self, flt: SafetyFilter, intervention_penalty: float = 0.0) -> None:
        """Add a safety-filter stage before the stages already there (an outer wrapper's filter
        acts first, as wrappers would), and its reward penalty ``c |u_safe - u_nominal|^2``."""
        check_scene_filter(self.scenario, flt)
        c = check_real(intervention_penalty, "intervention_penalty")
        if c < 0:
            raise ValueError(f"intervention_penalty = {shown(intervention_penalty)} must be >= 0")
        self.filters.insert(0, flt)
        self.penalties.append(c)
        # what the world reports is what the filter acting last (right before integration) uses
        last = self.filters[-1].config
        self.world_params.update(gamma=last.gamma, barrier=last.barrier, split=last.split)

    def set_theta(self, e: int, theta: Any) -> None:
        self.state.theta[e] = self.scenario.check_theta(theta)
        self.weights.update([e], self.state.theta, self.state.weighting)

    def set_weighting(self, e: int | None, weighting: Weighting) -> None:
        """Weighting of env e's running episode (all envs: None)."""
        envs = list(range(self.num_envs)) if e is None else [e]
        for i in envs:
            check_weighting(weighting, self.state.theta[i])  # all, before anything changes
        for i in envs:
            self.state.weighting[i] = weighting
        self.weights.update(envs, self.state.theta, self.state.weighting)

    # ---- episodes ---------------------------------------------------------------------------
    def check_options(self, options: dict | None) -> tuple[NDArray | None, Weighting]:
        """Theta (E, N) or None, and the weighting, from reset options
        (``rsvo_env.sim.reset_options.check_options``)."""
        return check_options(self, options)

    def reset(
        self,
        envs: Sequence[int] | NDArray[np.integer],
        seeds: Sequence[int | None],
        theta: NDArray | None = None,
        weighting: Weighting | None = None,
    ) -> None:
        """Start new episodes in ``envs``; env e draws from a generator seeded with its seed, or
        goes on with its own generator when the seed is None. ``theta``, ``weighting``: from
        ``check_options``. Nothing is written unless every env's start is valid."""
        sc = self.scenario
        weighting = self.weighting if weighting is None else weighting
        drawn = []
        for e, seed in zip(envs, seeds, strict=True):
            rng = self.rngs[e]
            if seed is not None or rng is None:
                rng, _ = seeding.np_random(seed)
            start, vel, goals = sc.initial_state(rng)
            obstacles = sc.obstacles(rng, start, goals)
            caps = np.zeros((0, 5)) if obstacles is None else obstacles.capsules
            check_scene(sc, start, goals, caps)
            th = sc.default_theta(rng) if theta is None else theta[e]
            drawn.append((e, rng, start, vel, goals, th, caps))
        s = self.state
        idx = np.array(envs, dtype=np.int64)
        for e, rng, start, vel, goals, th, caps in drawn:
            self.rngs[e] = rng
            s.obstacles[e] = caps
            s.positions[e], s.velocities[e], s.goals[e], s.starts[e] = start, vel, goals, start
            s.steered_velocities[e] = vel
            s.theta[e] = th
            s.weighting[e] = weighting
        self.weights.update(idx, s.theta, s.weighting)
        seg = s.goals[idx] - s.starts[idx]
        s.frame_angle[idx] = np.arctan2(seg[..., 1], seg[..., 0])
        s.headings[idx] = s.frame_angle[idx]  # a unicycle starts facing its goal
        # the stall clock first: the right-hand rule's hold reads it
        self.progress.reset(idx, goal_distance(s.positions[idx], s.goals[idx]))
        s.no_progress = self.progress.steps.copy()
        # what follows from the new positions: nearest distances and neighbours, who is at its
        # goal and whom the right-hand rule turns
        post_step.derive(self, idx)
        s.reached[idx] = s.at_goal[idx]
        self.metrics.reset(idx)

    def set_residual(self, residual: Residual | None) -> None:
        """Residual actions by ``residual``'s rule (None: off): each action is added to the
        scripted command, gated off near the goal (``rsvo_env.control.residual.Residual``)."""
        self.residual = residual

    def to_controls(self, actions: NDArray[np.float64]) -> NDArray[np.float64]:
        """Normalised actions (E, N, 2) to physical controls, by the model's map (the planar
        one: clip the norm to 1, scale by each agent's limit, rotate out of the goal frame);
        with residual actions, those controls added to the scripted command and held to each
        agent's bounds by the model (see ``set_residual``)."""
        sc = self.scenario
        model, params, limits = sc.model, sc.params, sc.agent_limits
        u = model.to_controls(actions, params, self._planar_controls, limits)
        if self.residual is not None:
            u = self.residual.controls(sc, self.state, u, lambda c: model.hold(c, params, limits))
        return u

    def _planar_controls(self, actions: NDArray[np.float64]) -> NDArray[np.float64]:
        limits = self.scenario.agent_limits
        if limits is None:
            u = planar.clip_norm(actions, 1.0, self.u_max)
        else:  # each agent its own bound
            u = planar.clip_norm(actions, 1.0) * limits[:, None]
        if self.frame == "goal":
            u = planar.rotate(u, self.state.frame_angle)
        return u

    def to_actions(self, controls: NDArray[np.float64]) -> NDArray[np.float64]:
        """Physical controls to the normalised action frame (no clipping)."""
        sc = self.scenario
        return sc.model.to_actions(controls, sc.params, self._planar_actions, sc.agent_limits)

    def _planar_actions(self, controls: NDArray[np.float64]) -> NDArray[np.float64]:
        limits = self.scenario.agent_limits
        u = controls / (self.u_max if limits is None else limits[:, None])
        if self.frame == "goal":
            u = planar.rotate(u, -self.state.frame_angle)
        return u

    def nominal_controls(self) -> NDArray[np.float64]:
        """The scripted controller's physical controls (E, N, 2) for the current state."""
        return self.scenario.nominal(self.state)

    def nominal_actions(self) -> NDArray[np.float64]:
        """The scripted controller's actions (E, N, A); with theta actions, the last component
        keeps each agent's theta (clipped to the range)."""
        a = self.to_actions(self.nominal_controls())
        if self.theta_action is None:
            return a
        return np.concatenate([a, self.theta_action.action(self.state.theta)[..., None]], -1)

    # ---- the step ---------------------------------------------------------------------------
    def _floor(self) -> Floor | None:
        """The weights' floor for the large-N pair search (``Weights.floor``)."""
        if self.n <= sizes.ALL_PAIRS_MAX_AGENTS:
            return None
        return self.weights.floor(self.state.theta, self.state.weighting)

    def _filter_bodies(self, flt: SafetyFilter) -> Bodies | None:
        """The scenario's bodies for ``flt`` (None: identical bodies, the filter's own)."""
        if self.plain:
            return None
        key = id(flt)
        if key not in self._bodies:
            same = bool(np.all(self.radii == 0.5 * flt.config.safety_radius))
            if same and self.scenario.agent_limits is None:
                self._bodies[key] = None  # the filter's own bodies are the scene's
                return None
            E, n, limits = self.num_envs, self.n, self.scenario.agent_limits
            radii = np.broadcast_to(self.radii, (E, n))
            u = None if limits is None else np.broadcast_to(limits, (E, n))
            self._bodies[key] = Bodies.of(flt.config, E, n, radii, u)
        return self._bodies[key]

    def apply_filters(
        self, u_nominal: NDArray[np.float64]
    ) -> tuple[NDArray, dict[str, Any] | None, NDArray]:
        """The filter stage: every filter in turn on the state about to be integrated. Returns
        the safe controls, the filters' stats (None without a filter) and the intervention
        ``|u_safe - u_nominal|``."""
        s = self.state
        if not self.filters:
            return u_nominal, None, np.zeros(u_nominal.shape[:-1])
        u, stats = u_nominal, None
        model = self.scenario.model
        vel = s.velocities if model.needs_velocities else None
        obstacles = s.obstacles if s.obstacles.shape[1] else None
        for flt in self.filters:
            res: FilterResult = flt.apply(
                s.positions,
                u,
                s.theta,
                vel,
                self.weights.matrix,
                known=KnownScenes(self.weights.omega_min, s.nearest, self._floor()),
                weighting=self.weights.pair_modes(s.weighting),
                bodies=self._filter_bodies(flt),
                obstacles=obstacles,
                **{name: getattr(s, name) for name in model.state_fields},
            )
            u = res.actions
            stats = merge_stats(stats, res)
        # one stage measured it already; stacked stages are measured end to end
        intervention = res.intervention if len(self.filters) == 1 else planar.norm(u - u_nominal)
        return u, stats, intervention

    def step(self, actions: NDArray[np.float64]) -> tuple[NDArray, NDArray, NDArray, NDArray, dict]:
        """One step of every env on validated normalised actions (E, N, A): A = 2, or 3 with
        theta actions (the scores of this step, and of its weights, come first).

        Returns observations (E, N, D) float32, rewards (E, N), terminated and truncated (E,),
        and the per-agent signals (E, N, ...) of ``signals``.
        """
        s, sc = self.state, self.scenario
        if self.theta_action is not None:
            s.theta[:] = self.theta_action.step_theta(actions[..., 2], s.theta)
            self.weights.update_all(s.theta, s.weighting)
            actions = actions[..., :2]
        u_nominal = self.to_controls(actions)
        u, stats, intervention = self.apply_filters(u_nominal)
        before, model = s.positions, sc.model
        model.advance_state(s, u, self.dt, sc.params)
        after = post_step.in_one_call if self.post_step_in_one_call else post_step.hook_by_hook
        reward, terminated, truncated = after(self, before, u_nominal, u, stats)
        penalty = sum(self.penalties)
        if penalty:
            reward = reward - penalty * intervention**2
        if self.reward_team:
            # each agent also shares its env's mean reward (the reward_team share of it)
            reward = reward + self.reward_team * (reward.mean(-1, keepdims=True) - reward)
        s.no_progress = self.progress.steps.copy()  # the after stage advanced the clock
        signals = self.signals(u_nominal, u, intervention, stats)
        return self.observe(), reward, terminated, truncated, signals

    def signals(self, *args: Any) -> dict[str, NDArray]:
        """Per-agent signals (E, N, ...) (``rsvo_env.sim.signals.signals``)."""
        return signals.signals(self, *args)

    def observe(self, envs: NDArray[np.int64] | None = None) -> NDArray[np.float32]:
        """Observations (E, N, D) of all envs, or of the given ones."""
        s = self.state
        # all envs: the arrays themselves, as a view of each costs more than it seems at a few
        # agents (this runs every step)
        fields: tuple[NDArray, ...]
        fields = (s.positions, s.velocities, s.goals, s.theta, s.neighbors, s.frame_angle)
        pick: NDArray[np.int64] | slice = slice(None)
        if envs is not None:
            pick = envs
            fields = tuple(a[envs] for a in fields)
        x, v, goals, theta, nb, angle = fields
        frame = angle if self.frame == "goal" else None
        omega, by_index = self.weights.neighbors(s.theta, s.weighting, nb, envs)
        obs = observation.observe(
            x,
            v,
            goals,
            theta,
            omega,
            nb,
            frame,
            self.radii,
            None if self.stall is None else self.stall.value(pick),
            by_index,
        )
        if not s.obstacles.shape[1]:
            return obs
        k_o = obstacle_observation.count(s.obstacles.shape[1])
        seen = obstacle_observation.observe(x, self.radii, s.obstacles[pick], frame, k_o)
        return np.concatenate([obs, seen.astype(np.float32)], axis=-1)
