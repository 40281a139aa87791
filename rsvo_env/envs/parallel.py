"""RSVOParallelEnv: the paper's scenarios as a PettingZoo ParallelEnv, the E = 1 dict adapter
over the simulation core (``rsvo_env.sim.core.Simulator``).

Every action goes through the safety filter (a stage of the core's step) unless
``safety_filter=False``; ``rsvo_env.wrappers.RCBFSafetyFilter`` adds a filter stage to an env
(``RSVOParallelEnv.add_safety_filter``).
"""

from __future__ import annotations

from collections import deque
from typing import Any

import gymnasium
import numpy as np
from gymnasium.utils import seeding
from numpy.typing import NDArray
from pettingzoo import ParallelEnv

from rsvo_env.control.residual import Residual
from rsvo_env.envs import global_state
from rsvo_env.envs.factory import make_simulator
from rsvo_env.envs.rendering import TRAIL, Renderer
from rsvo_env.envs.world import World
from rsvo_env.filter.safety import SafetyFilter
from rsvo_env.responsibility.svo import Weighting, check_weighting
from rsvo_env.scenarios import Scenario
from rsvo_env.sim.metrics import FLAT_FIELDS, EpisodeMetrics
from rsvo_env.util.validation import (
    check_action_dict,
    check_count,
    check_flag,
    check_seed,
    shown,
)


class EpisodeView:
    """The running episode of env e of an ``EpisodeMetrics``: ``steps``,
    ``deadlock_onset``, ``completed``, ... as plain values (None for an event not yet seen)."""

    def __init__(self, metrics: EpisodeMetrics, e: int = 0) -> None:
        self._metrics, self._e = metrics, e

    @property
    def steps(self) -> int:
        return int(self._metrics.steps[self._e])

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        return self._metrics.summary(self._e)[name]

    def summary(self) -> dict[str, Any]:
        return self._metrics.summary(self._e)


class RSVOParallelEnv(ParallelEnv):
    """N agents of one scenario, a PettingZoo ``ParallelEnv``; all stay alive until the episode
    ends for all together.

    Actions: ``Box(-1, 1, (2,))`` per agent; the env clips each action's norm to 1 and scales it
    by the scenario's ``u_max`` (velocity) or ``a_max`` (acceleration). Observations: float32,
    ``5 + 10 K`` values (``6 + 10 K`` with ``stall_clock``; ``rsvo_env.sim.observation``).
    Per-agent infos have the same keys, types and shapes at reset and at every step
    ([the core and its adapters](api.md)); the last finished episode's metrics are
    ``episode_metrics``.

    Args:
        scenario: A registered scenario's name (``rsvo_env.SCENARIOS``) or a ``Scenario``.
        render_mode: ``"human"``, ``"rgb_array"`` or None.
        render_size: The rendered frame's side, in pixels.
        keep_history: Keep every step's positions in ``history`` (the whole trajectory); by
            default only the last steps the renderer draws, so memory does not grow with the
            episode.
        record_series: Keep the per-step series the paper plots (each step's smallest and mean
            nearest distance in ``episode_metrics``); off by default, for the same reason.
        safety_filter: Every action through the R-CBF filter; False: the bare env, the action
            applied as given.
        **kwargs: The filter's ``gamma``, ``solver``, ``barrier``, ``split``,
            ``neighbor_radius``, ``intervention_penalty``; the env's ``num_obs_neighbors``,
            ``frame`` (``"goal"``: observed vectors and actions in each agent's start-to-goal
            frame), ``weighting``, ``reward_progress``, ``reward_time``, ``reward_goal``,
            ``reward_team``, ``stall_clock``, ``max_cycles`` (PettingZoo's name for
            ``max_steps``); and every scenario parameter.

    Raises:
        TypeError: An unknown keyword (naming it and the known ones).
        ValueError: A bad value, naming the field and the value.
    """

    metadata: dict[str, Any] = {
        "name": "rsvo_v0",
        "render_modes": ["human", "rgb_array"],
        "render_fps": 50,
        "is_parallelizable": True,
    }

    def __init__(
        self,
        scenario: str | Scenario = "circular_swap",
        render_mode: str | None = None,
        render_size: int = 600,
        keep_history: bool = False,
        record_series: bool = False,
        safety_filter: bool = True,
        **kwargs: Any,
    ) -> None:
        keep_history = check_flag(keep_history, "keep_history")
        record_series = check_flag(record_series, "record_series")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode = {shown(render_mode)}; use one of {self.metadata['render_modes']}"
            )
        self.sim = make_simulator(
            scenario, num_envs=1, record_series=record_series, safety_filter=safety_filter, **kwargs
        )
        self.scenario = self.sim.scenario
        # what print(env) shows, through any PettingZoo wrapper: the scenario, PettingZoo-style
        self.metadata = {**self.metadata, "name": f"rsvo_{self.scenario.name}_v0"}
        self.render_mode = render_mode
        self.render_size = check_count(render_size, "render_size", 16)
        n = self.scenario.num_agents
        self.possible_agents = [f"agent_{i}" for i in range(n)]
        self.agents: list[str] = []
        obs_space, act_space = self.sim.spaces()
        self.observation_spaces = {a: obs_space for a in self.possible_agents}
        self.action_spaces = {a: act_space for a in self.possible_agents}
        self.state_space = global_state.space(self.sim)
        self.history: deque[NDArray[np.float64]] = deque(maxlen=None if keep_history else TRAIL)
        self.renderer: Renderer | None = None
        self.episode_metrics: dict[str, Any] | None = None
        """The last finished episode's metrics (``docs/metrics.md``), None before one ends."""
        self._started = False
        self._info_keys: tuple[tuple[str, ...], tuple[str, ...]] | None = None

    # ---- what the core holds, seen for one env ----------------------------------------------
    frame = property(lambda self: self.sim.frame)
    num_obs_neighbors = property(lambda self: self.sim.k)
    max_steps = property(lambda self: self.sim.max_steps)
    dt = property(lambda self: self.sim.dt)

    @property
    def world(self) -> World | None:
        """Env state and parameters (read-only views); None before the first reset."""
        return World(self.sim, 0) if self._started else None

    @property
    def metrics(self) -> EpisodeView | None:
        """The running episode's metrics; None before the first reset."""
        return EpisodeView(self.sim.metrics, 0) if self._started else None

    @property
    def weighting(self) -> Weighting:
        return self.sim.weighting

    def set_weighting(self, mode: Weighting) -> None:
        """Weighting of this and later episodes (a reset option still overrides it once)."""
        check_weighting(mode, np.ones(self.sim.n))
        self.sim.weighting = mode
        if self._started:
            self.sim.set_weighting(0, mode)

    def set_residual(self, residual: Residual | None) -> None:
        """Residual actions by ``residual``'s rule, or off (None); see
        ``rsvo_env.wrappers.ResidualAction``."""
        self.sim.set_residual(residual)

    def add_safety_filter(self, flt: SafetyFilter, intervention_penalty: float = 0.0) -> None:
        """Turn on (another) filter stage of the core's step; see
        ``rsvo_env.wrappers.RCBFSafetyFilter``."""
        self.sim.add_filter(flt, intervention_penalty)

    def state(self) -> NDArray[np.float32]:
        """The global state (``state_space``'s layout: every agent's position, velocity, goal,
        theta and radius, then the obstacles; ``rsvo_env.envs.global_state``), for a centralised
        critic."""
        if not self._started:
            raise RuntimeError("call reset() before state()")
        return global_state.values(self.sim)[0]

    def observation_space(self, agent: str) -> gymnasium.spaces.Box:
        """An agent's observation space.

        Args:
            agent: The agent's name (``"agent_0"``, ...).

        Returns:
            ``Box`` of float32, the same for every agent.
        """
        return self.observation_spaces[agent]

    def action_space(self, agent: str) -> gymnasium.spaces.Box:
        """An agent's action space.

        Args:
            agent: The agent's name.

        Returns:
            ``Box(-1, 1, (2,))`` (with theta actions, one component more).
        """
        return self.action_spaces[agent]

    # ---- episode -----------------------------------------------------------------------------
    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, NDArray[np.float32]], dict[str, dict[str, Any]]]:
        """Start an episode.

        Args:
            seed: Seeds the env's own generators (starts, goals, theta draws); None: continue
                from the current ones.
            options: ``theta`` (the scores, one per agent) and ``weighting`` for this episode;
                other keys are not read (a warning says so once).

        Returns:
            Each agent's observation and info.

        Raises:
            ValueError: Bad options, naming the field and the value; the env is left as it was.
        """
        # Options are checked before any draw, so a refused reset leaves the generator as it was.
        seed = check_seed(seed)
        theta, weighting = self.sim.check_options(options)
        self.sim.reset([0], [seed], theta, weighting)
        self._started = True
        self.agents = list(self.possible_agents)
        self.history.clear()
        self.history.append(self.sim.state.positions[0].copy())
        obs = self._obs_dict(self.sim.observe())
        infos = self._infos(self.sim.signals())
        if self.render_mode == "human":
            self.render()
        return obs, infos

    def _require_running(self) -> None:
        if not self._started:
            raise RuntimeError("call reset() before step()")
        if not self.agents:
            raise RuntimeError("the episode is over; call reset()")

    def step(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        """Advance every agent one step, through the filter where it is on.

        Args:
            actions: Each live agent's action, in ``[-1, 1]`` per component.

        Returns:
            Observations, rewards, terminations, truncations and infos, each by agent.

        Raises:
            ValueError: A missing, unknown or malformed action (naming the agent and the
                value); the env is left as it was.
            RuntimeError: The episode has ended or not begun.
        """
        self._require_running()
        a = check_action_dict(actions, self.agents, (self.sim.action_width,))
        obs, reward, terminated, truncated, signals = self.sim.step(a[None])
        self.history.append(self.sim.state.positions[0].copy())
        agents = self.agents
        term, trunc = bool(terminated[0]), bool(truncated[0])
        rewards = dict(zip(agents, reward[0].tolist(), strict=True))
        terms = dict.fromkeys(agents, term)
        truncs = dict.fromkeys(agents, trunc)
        infos = self._infos(signals)
        if term or trunc:
            self.episode_metrics = self.sim.metrics.summary(0)
            self.agents = []
        if self.render_mode == "human":
            self.render()
        return self._obs_dict(obs), rewards, terms, truncs, infos

    def _obs_dict(self, obs: NDArray[np.float32]) -> dict[str, NDArray[np.float32]]:
        return dict(zip(self.possible_agents, obs[0], strict=True))

    def _infos(self, signals: dict[str, NDArray]) -> dict[str, dict[str, Any]]:
        """Per-agent infos: each signal's entry for the agent (vectors as rows of one copy per
        field), then the running episode's flat ``episode_*`` values."""
        if self._info_keys is None:
            self._info_keys = tuple(signals), tuple(f"episode_{k}" for k, _ in FLAT_FIELDS)
        keys, episode_keys = self._info_keys
        # tolist()[0], not [0].tolist(): no view made per field
        columns = [list(v[0].copy()) if v.ndim == 3 else v.tolist()[0] for v in signals.values()]
        episode = dict(zip(episode_keys, self.sim.metrics.flat_row(0), strict=True))
        # every column has one entry per agent: zip needs no length check
        rows = zip(*columns, strict=False)
        return {
            a: {**dict(zip(keys, vals, strict=False)), **episode}
            for a, vals in zip(self.possible_agents, rows, strict=False)
        }

    # ---- scripted controller -----------------------------------------------------------------
    def nominal_controls(self) -> NDArray[np.float64]:
        """The scripted controller's physical controls (N, 2) for the current state."""
        if not self._started:
            raise RuntimeError("call reset() first")
        return self.sim.nominal_controls()[0]

    def nominal_actions(self) -> dict[str, NDArray[np.float32]]:
        """The scripted controller's actions for the current step (the scenario's ``nominal``:
        move-to-goal and the right-hand rule, R-ORCA, or lane following).

        Returns:
            Each agent's action, as ``step`` takes it.

        Raises:
            RuntimeError: Before ``reset``.
        """
        if not self._started:
            raise RuntimeError("call reset() first")
        a = self.sim.nominal_actions()[0].astype(np.float32)
        return dict(zip(self.possible_agents, a, strict=True))

    def action_to_control(self, actions: NDArray[np.float64]) -> NDArray[np.float64]:
        """Normalised actions (N, 2) to physical controls (clip, scale, frame)."""
        return self.sim.to_controls(np.asarray(actions, dtype=np.float64)[None])[0]

    def control_to_action(self, controls: NDArray[np.float64]) -> NDArray[np.float64]:
        """Physical controls (N, 2) to the env's normalised action frame (no clipping)."""
        return self.sim.to_actions(np.asarray(controls, dtype=np.float64)[None])[0]

    # ---- rendering ---------------------------------------------------------------------------
    def render(self) -> NDArray[np.uint8] | None:
        """Draw the current step.

        Returns:
            An RGB frame (H, W, 3) in ``"rgb_array"`` mode; None in ``"human"`` mode (a
            window) or without a render mode.
        """
        if self.render_mode is None:
            gymnasium.logger.warn("render() called without a render_mode")
            return None
        if not self._started:
            raise RuntimeError("call reset() before render()")
        if self.renderer is None:
            self.renderer = Renderer(
                self.scenario.arena(),
                self.render_mode,
                size=self.render_size,
                fps=self.metadata["render_fps"],
                lanes=self.scenario.lanes(),
                caption=f"{self.scenario.name}, {self.sim.state.weighting[0]} weighting, "
                + ("filter on" if self.sim.filters else "no filter"),
            )
        s = self.sim.state
        self.renderer.draw(
            s.positions[0],
            s.goals[0],
            s.theta[0],
            self.sim.radii,
            self.history,
            time=self.sim.metrics.steps[0] * self.sim.dt,
            obstacles=s.obstacles[0],
            **{name: getattr(s, name)[0] for name in self.scenario.model.state_fields},
        )
        if self.render_mode == "rgb_array":
            return self.renderer.frame()
        self.renderer.show()
        return None

    def __getstate__(self) -> dict[str, Any]:
        # pygame surfaces cannot be copied or pickled: a copy makes its own on its next render()
        state = self.__dict__.copy()
        state["renderer"] = None
        return state

    def __repr__(self) -> str:
        filters = ", ".join(f"gamma={f.config.gamma:g} {f.config.solver}" for f in self.sim.filters)
        return (
            f"RSVOParallelEnv({shown(self.scenario.name)}, num_agents={self.sim.n}, "
            f"filter={'[' + filters + ']' if filters else 'off'})"
        )

    def close(self) -> None:
        """Close the renderer's window, if any."""
        if self.renderer is not None:
            self.renderer.close()
            self.renderer = None

    @property
    def np_random(self) -> np.random.Generator:
        rng = self.sim.rngs[0]
        if rng is None:
            rng, _ = seeding.np_random()
            self.sim.rngs[0] = rng
        return rng
