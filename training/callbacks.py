"""Stable-Baselines3 callbacks of a training run: the filter's episode statistics in the logs,
validation on held-out seeds, and a wall-clock budget."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback

from rsvo_env.training.seeded_episodes import (
    append_validation,
    intervened,
    model_policy,
    run_episodes,
    summarize,
    validation_score,
)


class EpisodeStats(BaseCallback):
    """Logs, over the episodes that ended since the last dump, under ``rollout/``: mean return
    per agent, success rate, completion time, intervention rate, collision steps (``cost``, an
    env's steps with a contact), an agent's episode cost (``episode_cost``: its steps in contact,
    OmniSafe's EpCost) and infeasible steps; and ``rollout/contact_agent_steps``, every agent-step
    in contact since training began. Read from each slot's info; an env's episode counts once
    (its first slot)."""

    def __init__(self, agents_per_env: int, u_max: float, dt: float) -> None:
        super().__init__()
        self.n, self.u_max, self.dt = agents_per_env, u_max, dt
        self.totals: dict[str, float] = {}

    def _on_training_start(self) -> None:
        slots = self.training_env.num_envs
        self.returns = np.zeros(slots)
        self.touched = np.zeros(slots)
        self.costs = np.zeros(slots)
        self.contacts = 0.0
        self.collisions = 0
        self.episodes: list[tuple[float, ...]] = []

    def _on_step(self) -> bool:
        infos, dones = self.locals["infos"], self.locals["dones"]
        self.returns += self.locals["rewards"]
        self.touched += intervened([i["intervention"] for i in infos], self.u_max)
        cost = np.array([i["cost"] for i in infos])
        self.costs += cost
        self.contacts += float(cost.sum())
        for k in np.flatnonzero(dones):
            if k % self.n:
                continue
            info, agents = infos[k], slice(k, k + self.n)
            steps = info["episode_steps"]
            completed = info["episode_completed"]
            self.episodes.append(
                (
                    float(self.returns[agents].mean()),
                    float(info["episode_success"]),
                    completed * self.dt if completed >= 0 else np.nan,
                    float(self.touched[agents].sum() / (steps * self.n)),
                    float(info["episode_collision_steps"]),
                    float(info["episode_infeasible"]),
                    float(self.costs[agents].mean()),
                )
            )
            self.collisions += info["episode_collision_steps"]
        self.returns[dones] = 0.0
        self.touched[dones] = 0.0
        self.costs[dones] = 0.0
        return True

    def _on_rollout_end(self) -> None:
        if not self.episodes:
            return
        rows = np.array(self.episodes)
        means = ("return", "success_rate", "completion_time", "intervention_rate", "cost")
        for j, name in [*enumerate(means), (6, "episode_cost")]:
            column = rows[:, j]
            if not np.isnan(column).all():
                self.logger.record(f"rollout/{name}", float(np.nanmean(column)))
        self.logger.record("rollout/infeasible_steps", float(rows[:, 5].sum()))
        self.logger.record("rollout/collision_steps_total", int(self.collisions))
        self.logger.record("rollout/contact_agent_steps", self.contacts)
        self.episodes = []


# OmniSafe's columns: EpRet, EpCost, EpLen
EPISODE = ("episode_return", "episode_cost", "episode_length")


class Validation(BaseCallback):
    """Every ``every`` agent-steps: the deterministic policy on the held-out seeds
    ``seed, seed + 1, ...``, logged under ``eval/`` and appended to ``validation.csv``; the best
    model so far (success rate, then completion time) is saved as ``best_model.zip``."""

    def __init__(self, cfg: dict[str, Any], out: Path) -> None:
        super().__init__()
        val = cfg["validation"]
        self.cfg, self.out = cfg, out
        self.every, self.episodes, self.seed = val["every"], val["episodes"], val["seed"]
        self.next_at = self.every
        self.best: tuple[float, float] | None = None

    def _on_step(self) -> bool:
        if self.every and self.num_timesteps >= self.next_at:
            self.next_at += self.every
            self.validate()
        return True

    def validate(self) -> dict[str, float]:
        policy = model_policy(self.model)
        stats = summarize(run_episodes(self.cfg, policy, self.episodes, self.seed))
        for key in ("success_rate", "completion_time", "collisions", "infeasible", *EPISODE):
            self.logger.record(f"eval/{key}", stats[key])
        append_validation(self.out / "validation.csv", self.num_timesteps, stats)
        score = validation_score(stats)
        if self.best is None or score > self.best:
            self.best = score
            self.model.save(self.out / "best_model.zip")
        return stats


class Progress(BaseCallback):
    """A progress bar over the run's budget, whichever part ends it: the share done is the
    larger of the agent-steps taken over ``timesteps`` and the seconds spent over ``seconds``
    (the ``--time-limit``), so the bar fills exactly when training stops and its time left is
    the nearer of the two ends. (SB3's own bar counts steps only.)"""

    def __init__(self, timesteps: int, seconds: float | None, file: Any = None) -> None:
        super().__init__()
        self.timesteps, self.seconds, self.file = int(timesteps), seconds, file
        self.start = time.perf_counter()
        self.bar: Any = None
        self.shown = 0.0

    def fraction(self, steps: int, elapsed: float) -> float:
        """The share of the budget used after ``steps`` agent-steps and ``elapsed`` seconds."""
        used = steps / self.timesteps
        if self.seconds is not None:
            used = max(used, elapsed / self.seconds)
        return min(used, 1.0)

    def _on_training_start(self) -> None:
        from tqdm.auto import tqdm

        self.start = time.perf_counter()
        self.bar = tqdm(
            total=100.0,
            unit="%",
            file=self.file,
            bar_format=("{percentage:5.1f}%|{bar}| {desc} [{elapsed}<{remaining}]"),
        )

    def _on_step(self) -> bool:
        self._show(self.num_timesteps)
        return True

    def _show(self, steps: int, done: float | None = None) -> None:
        if done is None:
            done = 100.0 * self.fraction(steps, time.perf_counter() - self.start)
        if done - self.shown >= 0.1 or done >= 100.0:
            self.bar.update(done - self.shown)
            self.shown = done
            limit = "" if self.seconds is None else f", limit {self.seconds:g} s"
            self.bar.set_description_str(f"{steps:,}/{self.timesteps:,} agent-steps{limit}")

    def _on_training_end(self) -> None:
        # training ends when the steps or the time run out: the budget is used up either way
        self._show(self.num_timesteps, 100.0)
        self.bar.close()


class TimeLimit(BaseCallback):
    """Stops training once ``seconds`` of wall-clock time have passed (checked every step)."""

    def __init__(self, seconds: float | None) -> None:
        super().__init__()
        self.seconds = seconds
        self.start = time.perf_counter()
        self.hit = False

    def _on_training_start(self) -> None:
        self.start = time.perf_counter()

    def _on_step(self) -> bool:
        if self.seconds is not None and time.perf_counter() - self.start > self.seconds:
            self.hit = True
            return False
        return True
