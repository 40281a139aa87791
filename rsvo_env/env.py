"""RSVOParallelEnv: the paper's scenarios as a PettingZoo ParallelEnv (DESIGN.md section 2).

The env has no safety filter of its own; ``wrappers.RCBFSafetyFilter`` adds it. It exposes what
the filter needs through ``env.unwrapped.world`` and takes the filter's safe controls through
:meth:`RSVOParallelEnv.set_next_controls`, so that wrappers stacked in between still see the
step.
"""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
from gymnasium.utils import seeding
from numpy.typing import NDArray
from pettingzoo import ParallelEnv

from rsvo_env import dynamics, metrics, nominal
from rsvo_env.neighbors import nearest_distance
from rsvo_env.rendering import Renderer
from rsvo_env.responsibility import Weighting, weight_matrix
from rsvo_env.scenarios import Scenario, make_scenario
from rsvo_env.validation import check_action_dict, check_vectors
from rsvo_env.world import World

FRAMES = ("world", "goal")
RESET_OPTIONS = ("theta", "weighting")
OWN_FEATURES = 5  # goal offset (2), own velocity (2), own theta
NEIGHBOR_FEATURES = 8  # rel. position (2), rel. velocity (2), omega_ij, theta_j, gap, present


class RSVOParallelEnv(ParallelEnv):
    """N agents of one scenario; all stay alive until the episode ends for all together.

    Actions: ``Box(-1, 1, (2,))`` per agent; the env clips each action's norm to 1 and scales it
    by the scenario's ``u_max`` (velocity) or ``a_max`` (acceleration). Observations: float32,
    ``5 + 8 K`` values (goal offset, own velocity, own theta, then the K nearest neighbours'
    relative position, relative velocity, omega_ij, theta_j, gap ``|d| - R`` and a present
    flag). ``frame="goal"`` rotates observed vectors and actions into each agent's own
    start-to-goal frame.
    """

    metadata = {
        "name": "rsvo_v0",
        "render_modes": ["human", "rgb_array"],
        "render_fps": 50,
        "is_parallelizable": True,
    }

    def __init__(
        self,
        scenario: str | Scenario = "circular_swap",
        render_mode: str | None = None,
        num_obs_neighbors: int | None = None,
        frame: str = "world",
        weighting: Weighting = "asymmetric",
        reward_progress: float = 1.0,
        reward_time: float = 0.01,
        reward_goal: float = 10.0,
        render_size: int = 600,
        **scenario_kwargs: Any,
    ) -> None:
        self.scenario = make_scenario(scenario, **scenario_kwargs)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode = {render_mode!r}; use one of {self.metadata['render_modes']}"
            )
        if frame not in FRAMES:
            raise ValueError(f"frame = {frame!r}; use one of {FRAMES}")
        n = self.scenario.num_agents
        if num_obs_neighbors is None:
            num_obs_neighbors = min(n - 1, 6)
        if not isinstance(num_obs_neighbors, (int, np.integer)) or not 0 <= num_obs_neighbors < n:
            raise ValueError(f"num_obs_neighbors = {num_obs_neighbors!r} must be in [0, {n - 1}]")
        weight_matrix(np.ones(n), weighting)  # validates the mode now, not at the first reset
        self.render_mode = render_mode
        self.frame = frame
        self.num_obs_neighbors = int(num_obs_neighbors)
        self.weighting: Weighting = weighting
        self.reward_progress = float(reward_progress)
        self.reward_time = float(reward_time)
        self.reward_goal = float(reward_goal)
        self.render_size = int(render_size)
        self.possible_agents = [f"agent_{i}" for i in range(n)]
        self.agents: list[str] = []
        self.max_steps = int(self.scenario.params["max_steps"])
        self.dt = float(self.scenario.params["dt"])
        self._build_spaces()
        self._np_random: np.random.Generator | None = None
        self.world: World | None = None
        self.metrics: metrics.EpisodeMetrics | None = None
        self.history: list[NDArray[np.float64]] = []
        self.renderer: Renderer | None = None
        self._next_controls: tuple[NDArray[np.float64], dict[str, Any] | None] | None = None

    # ---- spaces ------------------------------------------------------------------------------
    def _bounds(self) -> tuple[float, float]:
        """Finite bounds on every position and velocity component reachable in an episode."""
        sc = self.scenario
        lo, hi = sc.arena()  # holds every start and goal
        horizon = self.max_steps * self.dt
        extent = float(max(np.abs(lo).max(), np.abs(hi).max()))
        if sc.dynamics == "double_integrator":
            v0 = float(sc.params.get("v0", 0.0))
            v = v0 + sc.u_max * horizon
            p = extent + v0 * horizon + 0.5 * sc.u_max * horizon**2
        else:
            v = sc.u_max
            p = extent + v * horizon
        return p, v

    def _build_spaces(self) -> None:
        p, v = self._bounds()
        # vectors may be rotated into the goal frame: a component can grow by sqrt(2)
        r2 = np.sqrt(2.0)
        R = self.scenario.params["safety_radius"]
        own_hi = [2 * p * r2] * 2 + [v * r2] * 2 + [self.scenario.params["theta_max"]]
        own_lo = [-x for x in own_hi[:4]] + [0.0]
        nb_hi = (
            [2 * p * r2] * 2
            + [2 * v * r2] * 2
            + [1.0, self.scenario.params["theta_max"], 2 * p * r2, 1.0]
        )
        nb_lo = [-x for x in nb_hi[:4]] + [0.0, 0.0, -R, 0.0]
        K = self.num_obs_neighbors
        low = np.array(own_lo + nb_lo * K, dtype=np.float32)
        high = np.array(own_hi + nb_hi * K, dtype=np.float32)
        obs_space = gymnasium.spaces.Box(low, high, dtype=np.float32)
        act_space = gymnasium.spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
        self.observation_spaces = {a: obs_space for a in self.possible_agents}
        self.action_spaces = {a: act_space for a in self.possible_agents}

    def observation_space(self, agent: str) -> gymnasium.spaces.Box:
        return self.observation_spaces[agent]

    def action_space(self, agent: str) -> gymnasium.spaces.Box:
        return self.action_spaces[agent]

    # ---- episode -----------------------------------------------------------------------------
    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, NDArray[np.float32]], dict[str, dict[str, Any]]]:
        # Other keys are left for wrappers (PettingZoo's own API test passes one of its own).
        options = dict(options or {})
        sc = self.scenario
        # Options are checked before any draw, so a refused reset leaves the generator as it was.
        theta = sc.check_theta(options["theta"]) if "theta" in options else None
        weighting = options.get("weighting", self.weighting)
        weight_matrix(np.ones(sc.num_agents) if theta is None else theta, weighting)
        if seed is not None or self._np_random is None:
            self._np_random, _ = seeding.np_random(seed)
        start, vel, goals = sc.initial_state(self._np_random)
        self._check_start(start)
        if theta is None:
            theta = sc.default_theta(self._np_random)
        p = sc.params
        self.world = World(
            positions=start.copy(),
            velocities=vel.copy(),
            goals=goals.copy(),
            theta=theta,
            safety_radius=p["safety_radius"],
            u_max=sc.u_max,
            dt=self.dt,
            dynamics=sc.dynamics,
            gamma=p["gamma"],
            goal_tolerance=p["goal_tolerance"],
            barrier=p.get("barrier", "braking"),
            split=p.get("split", "capability"),
            weighting=weighting,
            neighbor_k=max(self.num_obs_neighbors, 1),
        )
        seg = goals - start
        self._frame_angle = np.arctan2(seg[:, 1], seg[:, 0])
        self.agents = list(self.possible_agents)
        self.metrics = metrics.EpisodeMetrics(sc.num_agents, self.dt, p["safety_radius"])
        self.history = [start.copy()]
        self._reached = sc.at_goal(start, goals)
        self._next_controls = None
        obs = self._observe()
        infos = {a: {"at_goal": bool(self._reached[i])} for i, a in enumerate(self.agents)}
        if self.render_mode == "human":
            self.render()
        return obs, infos

    def _check_start(self, start: NDArray[np.float64]) -> None:
        """Starting positions must be in the safe set: every pair at least R apart."""
        R = self.scenario.params["safety_radius"]
        d = nearest_distance(start)
        if np.any(d < R):
            i = int(np.argmin(d))
            j = int(np.argsort(np.linalg.norm(start - start[i], axis=1))[1])
            raise ValueError(
                f"starting positions of agents {i} and {j} overlap: distance "
                f"{float(d[i])!r} < safety_radius {R} (h < 0)"
            )

    def set_next_controls(
        self, controls: NDArray[np.float64], filter_stats: dict[str, Any] | None = None
    ) -> None:
        """Apply these physical controls (N, 2) at the next step instead of the actions' own.

        The safety filter's channel: it calls this, then ``step(actions)`` down the wrapper
        stack with the nominal actions, so every wrapper in between sees the step. The controls
        are used once. ``filter_stats`` (``feasible``, ``n_unrecoverable_pairs``,
        ``n_capped_shares``, ``min_h``) go into the episode metrics.
        """
        self._require_running()
        u = check_vectors(controls, "controls", self.world.n, self.possible_agents)
        self._next_controls = (u, filter_stats)

    def action_to_control(self, actions: NDArray[np.float64]) -> NDArray[np.float64]:
        """Normalised actions (N, 2) to physical controls: clip the norm to 1, scale by u_max,
        rotate out of the goal frame."""
        u = nominal.clip_norm(actions, 1.0) * self.world.u_max
        if self.frame == "goal":
            u = nominal.rotate(u, self._frame_angle)
        return u

    def control_to_action(self, controls: NDArray[np.float64]) -> NDArray[np.float64]:
        """Physical controls to the env's normalised action frame (no clipping)."""
        u = controls / self.world.u_max
        if self.frame == "goal":
            u = nominal.rotate(u, -self._frame_angle)
        return u

    def _require_running(self) -> None:
        if self.world is None:
            raise RuntimeError("call reset() before step()")
        if not self.agents:
            raise RuntimeError("the episode is over; call reset()")

    def step(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        self._require_running()
        a = check_action_dict(actions, self.agents)
        requested = self.action_to_control(a)
        if self._next_controls is not None:
            applied, stats = self._next_controls
            self._next_controls = None
        else:
            applied, stats = requested, None
        w, sc = self.world, self.scenario
        before = w.positions
        if w.dynamics == "double_integrator":
            w.positions, w.velocities = dynamics.double_integrator_step(
                w.positions, w.velocities, applied, self.dt
            )
        else:
            w.positions = dynamics.single_integrator_step(w.positions, applied, self.dt)
            w.velocities = applied.copy()
        self.history.append(w.positions.copy())
        nearest = w.nearest_distance()
        at_goal = sc.at_goal(w.positions, w.goals)
        rh = (
            sc.right_hand_active(w)
            if sc.params["deadlock_resolution"] == "right_hand"
            else (np.zeros(w.n, dtype=bool))
        )
        self.metrics.update(
            w.positions - before,
            nearest,
            rh,
            metrics.passed_midpoint(w.positions, w.starts, w.goals),
            at_goal,
            requested,
            applied,
            stats,
        )
        progress = np.linalg.norm(before - w.goals, axis=1) - np.linalg.norm(
            w.positions - w.goals, axis=1
        )
        first_arrival = at_goal & ~self._reached
        self._reached |= at_goal
        reward = (
            self.reward_progress * progress - self.reward_time + self.reward_goal * first_arrival
        )
        terminated = bool(at_goal.all())
        truncated = not terminated and self.metrics.steps >= self.max_steps
        cost = nearest < w.safety_radius - 1e-9
        agents = self.agents
        obs = self._observe()
        rewards = dict(zip(agents, reward.tolist(), strict=True))
        terms = {a: terminated for a in agents}
        truncs = {a: truncated for a in agents}
        u_applied = applied.copy()  # one copy a step; each agent's entry is a row of it
        infos = {
            a: {
                "min_distance": d,
                "cost": c,
                "at_goal": g,
                "rh_active": r,
                "u_applied": u_applied[i],
            }
            for i, (a, d, c, g, r) in enumerate(
                zip(
                    agents,
                    nearest.tolist(),
                    cost.astype(float).tolist(),
                    at_goal.tolist(),
                    rh.tolist(),
                    strict=True,
                )
            )
        }
        if terminated or truncated:
            summary = self.metrics.summary()
            for a in agents:
                infos[a]["episode"] = summary
            self.agents = []
        if self.render_mode == "human":
            self.render()
        return obs, rewards, terms, truncs, infos

    # ---- observations ------------------------------------------------------------------------
    def _observe(self) -> dict[str, NDArray[np.float32]]:
        w = self.world
        x, v = w.positions, w.velocities
        nb = w.neighbors(self.num_obs_neighbors)[1][:, : self.num_obs_neighbors]
        rel_p = x[nb] - x[:, None, :]
        rel_v = v[nb] - v[:, None, :]
        goal = w.goals - x
        vel = v
        if self.frame == "goal":
            ang = -self._frame_angle
            goal, vel = nominal.rotate(goal, ang), nominal.rotate(vel, ang)
            rel_p = nominal.rotate(rel_p, ang[:, None])
            rel_v = nominal.rotate(rel_v, ang[:, None])
        n, K = nb.shape
        rows = np.arange(n)[:, None]
        gap = np.linalg.norm(rel_p, axis=2) - w.safety_radius
        neigh = np.concatenate(
            [
                rel_p,
                rel_v,
                w.omega[rows, nb][..., None],
                w.theta[nb][..., None],
                gap[..., None],
                np.ones((n, K, 1)),
            ],
            axis=2,
        ).reshape(n, K * NEIGHBOR_FEATURES)
        obs = np.concatenate([goal, vel, w.theta[:, None], neigh], axis=1).astype(np.float32)
        return {a: obs[i] for i, a in enumerate(self.possible_agents)}

    # ---- scripted controller -----------------------------------------------------------------
    def nominal_controls(self) -> NDArray[np.float64]:
        """The scripted controller's physical controls (N, 2) for the current state."""
        if self.world is None:
            raise RuntimeError("call reset() first")
        return self.scenario.nominal(self.world)

    def nominal_actions(self) -> dict[str, NDArray[np.float32]]:
        """The scripted move-to-goal (+ right-hand rule, or lane following) as env actions."""
        a = self.control_to_action(self.nominal_controls()).astype(np.float32)
        return {agent: a[i] for i, agent in enumerate(self.possible_agents)}

    # ---- rendering ---------------------------------------------------------------------------
    def render(self) -> NDArray[np.uint8] | None:
        if self.render_mode is None:
            gymnasium.logger.warn("render() called without a render_mode")
            return None
        if self.world is None:
            raise RuntimeError("call reset() before render()")
        if self.renderer is None:
            self.renderer = Renderer(
                self.scenario.arena(),
                self.render_mode,
                size=self.render_size,
                fps=self.metadata["render_fps"],
            )
        w = self.world
        self.renderer.draw(w.positions, w.goals, w.theta, w.safety_radius, self.history)
        if self.render_mode == "rgb_array":
            return self.renderer.frame()
        self.renderer.show()
        return None

    def close(self) -> None:
        if self.renderer is not None:
            self.renderer.close()
            self.renderer = None

    @property
    def np_random(self) -> np.random.Generator:
        if self._np_random is None:
            self._np_random, _ = seeding.np_random()
        return self._np_random
