"""Seeded evaluation of a policy or of the scripted controller, with the filter on.

Episode k of an evaluation with seed s is env k of a ``BatchedEnv`` reset with seed s (so it is
seeded ``s + k``): a learned policy and the scripted controller meet the same starts, thetas,
dt, speed limit and time cap, and their results pair up seed by seed.
"""

from __future__ import annotations

import csv
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rsvo_env.training.config import make_env, make_parallel

Policy = Callable[[NDArray[np.float32], Any], NDArray]
# the per-episode records an evaluation returns, one array of length `episodes` each
FIELDS = (
    "success",
    "completion_time",
    "collision_steps",
    "min_distance",
    "infeasible",
    "return",
    "intervention",
    "intervention_rate",
    "steps",
    "arrived",
    "cost",
)


def intervened(intervention: Any, u_max: float) -> Any:
    """Whether the filter changed a command: by more than 1e-6 of the speed limit."""
    return np.asarray(intervention) > 1e-6 * u_max


def validation_score(stats: dict[str, float]) -> tuple[float, float]:
    """How validations rank (higher is better): success rate, then a shorter completion."""
    fastest = -stats["completion_time"] if stats["success_rate"] > 0 else -np.inf
    return stats["success_rate"], fastest


def append_validation(path: Any, timesteps: int, stats: dict[str, float]) -> None:
    """One row of ``validation.csv`` (header on the first): the agent-steps so far and the
    validation's statistics; the same file from the SB3 and the RLlib paths."""
    path = Path(path)
    row = {"timesteps": int(timesteps), **stats}
    new = not path.exists()
    with open(path, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(row))
        if new:
            writer.writeheader()
        writer.writerow(row)


def model_policy(model: Any) -> Policy:
    """A Stable-Baselines3 model's deterministic action for every agent (parameter sharing)."""

    def act(obs: NDArray[np.float32], env: Any) -> NDArray:
        flat = obs.reshape(-1, obs.shape[-1])
        return model.predict(flat, deterministic=True)[0].reshape(*obs.shape[:-1], -1)

    return act


def scripted_policy(obs: NDArray[np.float32], env: Any) -> NDArray:
    """The scripted controller's command (move-to-goal and the right-hand rule)."""
    return env.nominal_actions()


def evaluation_cap(cfg: dict[str, Any]) -> int:
    """The time cap (steps) of validation and evaluation episodes: ``validation.max_steps``, or
    the training episodes' ``env.max_steps`` (or the scenario's default)."""
    cap = cfg.get("validation", {}).get("max_steps")
    return cap if cap is not None else make_env(cfg, num_envs=1).sim.max_steps


def run_episodes(
    cfg: dict[str, Any],
    policy: Policy,
    episodes: int,
    seed: int,
    action: str | None = None,
    weighting: str | None = None,
) -> dict[str, NDArray]:
    """One episode per seed ``seed, ..., seed + episodes - 1``, all stepped together, each
    capped at ``evaluation_cap`` steps."""
    cap = evaluation_cap(cfg)
    env = make_env(cfg, num_envs=episodes, action=action, weighting=weighting, max_steps=cap)
    obs, _ = env.reset(seed=seed)
    dt, u_max = env.scenario.params["dt"], env.scenario.u_max
    E, N = env.num_envs, env.num_agents
    out = {k: np.zeros(E) for k in FIELDS}
    returns, effort, touched = np.zeros((E, N)), np.zeros((E, N)), np.zeros((E, N))
    costs = np.zeros((E, N))
    finished = np.zeros(E, dtype=bool)
    residual = env.sim.residual
    # agent-steps short of the goal, and those in which the policy's residual acted
    en_route, acted = np.zeros(E), np.zeros(E)
    while not finished.all():
        if residual is not None:
            short = ~env.sim.state.reached
            en_route += short.sum(axis=1) * ~finished
            acted += (residual.acting(env.scenario, env.sim.state) & short).sum(axis=1) * ~finished
        obs, reward, _, _, info = env.step(policy(obs, env))
        live = ~finished
        returns[live] += reward[live]
        effort[live] += info["intervention"][live]
        costs[live] += info["cost"][live]
        touched[live] += intervened(info["intervention"][live], u_max)
        ended = info["_final_obs"] & live
        if ended.any():
            steps = info["episode_steps"][ended]
            out["success"][ended] = info["episode_success"][ended]
            done_at = info["episode_completed"][ended]
            out["completion_time"][ended] = np.where(done_at >= 0, done_at * dt, np.nan)
            out["collision_steps"][ended] = info["episode_collision_steps"][ended]
            out["min_distance"][ended] = info["episode_min_distance"][ended]
            out["infeasible"][ended] = info["episode_infeasible"][ended]
            out["return"][ended] = returns[ended].mean(axis=1)
            out["cost"][ended] = costs[ended].mean(axis=1)
            out["intervention"][ended] = effort[ended].sum(axis=1) / (steps * N)
            out["intervention_rate"][ended] = touched[ended].sum(axis=1) / (steps * N)
            out["steps"][ended] = steps
            out["arrived"][ended] = info["episode_arrived"][ended] / N
            finished |= ended
    out["safety_radius"] = np.full(E, env.scenario.params["safety_radius"])
    if residual is not None:
        out["residual_share"] = acted / np.maximum(en_route, 1)
    return out


def summarize(records: dict[str, NDArray]) -> dict[str, float]:
    """Means over episodes (completion time over the successful ones)."""
    ok = records["success"].astype(bool)
    return {
        "episodes": int(len(ok)),
        "success_rate": float(ok.mean()),
        # the share of agents that reached their goals, over all episodes
        "arrived": float(records["arrived"].mean()),
        "completion_time": float(np.nanmean(records["completion_time"])) if ok.any() else np.nan,
        "collisions": int(records["collision_steps"].sum()),
        "min_distance": float(records["min_distance"].min()),
        "infeasible": int(records["infeasible"].sum()),
        # OmniSafe's EpRet, EpCost, EpLen: an agent's episode return and cost (a step in contact
        # costs 1), means over agents and episodes, and the episode's length in steps
        "episode_return": float(records["return"].mean()),
        "episode_cost": float(records["cost"].mean()),
        "episode_length": float(records["steps"].mean()),
        "intervention": float(records["intervention"].mean()),
        "intervention_rate": float(records["intervention_rate"].mean()),
        # residual actions: the share of agent-steps short of the goal in which the residual acted
        **(
            {"residual_share": float(records["residual_share"].mean())}
            if "residual_share" in records
            else {}
        ),
    }


def paired(policy: dict[str, NDArray], scripted: dict[str, NDArray]) -> dict[str, float]:
    """Completion time of the policy minus the scripted controller's, seed by seed, over the
    seeds both finish: mean difference, its standard error, and the relative change of the means
    (negative: the policy is faster)."""
    both = policy["success"].astype(bool) & scripted["success"].astype(bool)
    a, b = policy["completion_time"][both], scripted["completion_time"][both]
    n = int(both.sum())
    diff = a - b
    return {
        "paired_seeds": n,
        "mean_difference": float(diff.mean()) if n else np.nan,
        "standard_error": float(diff.std(ddof=1) / np.sqrt(n)) if n > 1 else np.nan,
        "relative_change": float(a.mean() / b.mean() - 1.0) if n else np.nan,
        "relative_standard_error": float(diff.std(ddof=1) / np.sqrt(n) / b.mean())
        if n > 1
        else np.nan,
    }


def record_gif(
    cfg: dict[str, Any],
    policy: Policy,
    seed: int,
    path: str,
    action: str | None = None,
    fps: int = 10,
) -> str:
    """One seeded episode of the filtered ParallelEnv, driven by ``policy``, as a GIF played at
    ``fps`` frames a second (one frame a step: real time when ``fps = 1 / dt``), capped as the
    evaluation's episodes are (``evaluation_cap``)."""
    from rsvo_env.envs.rendering import save_gif

    cfg = {**cfg, "env": {**cfg["env"], "max_steps": evaluation_cap(cfg)}}
    env = make_parallel(cfg, render_mode="rgb_array", action=action)
    obs, _ = env.reset(seed=seed)
    agents = list(env.possible_agents)
    frames = [env.render()]
    while env.agents:
        stacked = np.stack([obs[a] for a in agents])[None]
        actions = np.asarray(policy(stacked, _Nominal(env)))[0]
        obs, *_ = env.step(dict(zip(agents, actions, strict=True)))
        frames.append(env.render())
    env.close()
    return str(save_gif(frames, path, fps=fps))


class _Nominal:
    """What ``scripted_policy`` reads, for a ParallelEnv: its nominal actions as an array."""

    def __init__(self, env: Any) -> None:
        self.env = env

    def nominal_actions(self) -> NDArray:
        acts = self.env.unwrapped.nominal_actions()
        return np.stack([acts[a] for a in self.env.possible_agents])[None]
