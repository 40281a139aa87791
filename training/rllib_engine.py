"""Training on Ray RLlib (the ``distributed`` extra): the same configs, logs and evaluation as the
SB3 path, PPO with one RLModule shared by every agent.

``train_rllib`` builds RLlib's PPO from a resolved config (its ``rllib`` section), on a local Ray
instance or on a running cluster (``address``), with ``num_env_runners`` sampling processes of
``num_envs_per_env_runner`` envs each. Every iteration appends to ``progress.csv`` (and TensorBoard
when installed); validation runs our own protocol (``rsvo_env.training.seeded_episodes``) on the
shared module; checkpoints are RLlib's (``checkpoint/``, ``best_checkpoint/``,
``checkpoints/step_N``), beside the run's ``config.yaml``.
"""

from __future__ import annotations

import csv
import json
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

from rsvo_env.training import config as configs
from rsvo_env.training.seeded_episodes import (
    append_validation,
    run_episodes,
    summarize,
    validation_score,
)

SHARED = "shared"


def shared_policy(agent_id: Any, *args: Any, **kwargs: Any) -> str:
    """Every agent maps to the one shared module (parameter sharing)."""
    return SHARED


def module_policy(module: Any) -> Any:
    """The shared module's deterministic action (the Gaussian's mean) for every agent."""
    import torch

    def act(obs: np.ndarray, env: Any) -> np.ndarray:
        flat = torch.as_tensor(obs.reshape(-1, obs.shape[-1]), dtype=torch.float32)
        with torch.no_grad():
            out = module.forward_inference({"obs": flat})["action_dist_inputs"]
        # the Gaussian's inputs are the means, then the log-stds: as many of each as actions
        width = out.shape[1] // 2
        return out[:, :width].numpy().reshape(*obs.shape[:-1], width)

    return act


def load_module(checkpoint: str | Path) -> Any:
    """The shared RLModule of an RLlib checkpoint written by ``train_rllib``."""
    from ray.rllib.core.rl_module.rl_module import RLModule

    return RLModule.from_checkpoint(
        Path(checkpoint).resolve() / "learner_group" / "learner" / "rl_module" / SHARED
    )


def build(cfg: dict[str, Any], num_env_runners: int, num_envs_per_env_runner: int) -> Any:
    """RLlib's PPO config for a resolved training config."""
    from ray.rllib.algorithms.ppo import PPOConfig

    from rsvo_env.training.rllib_callbacks import EpisodeMetrics
    from rsvo_env.training.rllib_env import RSVOMultiAgentEnv

    r = cfg["rllib"]
    one_thread = {
        key: str(cfg["threads"])
        for key in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS", "RSVO_NUM_THREADS")
    }
    return (
        PPOConfig()
        .environment(RSVOMultiAgentEnv, env_config={"cfg": cfg})
        .multi_agent(policies={SHARED}, policy_mapping_fn=shared_policy)
        .env_runners(
            num_env_runners=num_env_runners,
            num_envs_per_env_runner=num_envs_per_env_runner,
            num_cpus_per_env_runner=1,
        )
        .training(
            lr=r["lr"],
            gamma=r["gamma"],
            lambda_=r["lambda"],
            clip_param=r["clip_param"],
            train_batch_size_per_learner=r["train_batch_size"],
            minibatch_size=r["minibatch_size"],
            num_epochs=r["num_epochs"],
        )
        .rl_module(model_config={"fcnet_hiddens": list(r["hiddens"])})
        .callbacks(EpisodeMetrics)
        .python_environment(
            extra_python_environs_for_driver=one_thread,
            extra_python_environs_for_worker=one_thread,
        )
        .debugging(seed=cfg["seed"])
    )


def agent_steps(result: dict[str, Any]) -> int:
    value = result["env_runners"].get("num_agent_steps_sampled_lifetime", 0)
    return int(sum(value.values()) if isinstance(value, dict) else value)


def train_rllib(
    cfg: dict[str, Any],
    out: str | Path,
    time_limit: float | None = None,
    num_env_runners: int = 0,
    num_envs_per_env_runner: int = 1,
    address: str | None = None,
) -> dict[str, Any]:
    """Train as ``cfg`` says into ``out`` with RLlib; returns the summary (``summary.json``)."""
    import ray

    out = Path(out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    configs.save(cfg, out / "config.yaml")
    configs.limit_threads(cfg["threads"])
    os.environ.setdefault("RAY_DEDUP_LOGS", "0")
    ray.init(address=address, include_dashboard=False, log_to_driver=False)
    try:
        algo = build(cfg, num_env_runners, num_envs_per_env_runner).build_algo()
        log = Log(out)
        val = cfg["validation"]
        next_val, next_ckpt = val["every"], cfg["checkpoint_every"]
        best: tuple[float, float] | None = None
        start, steps, stopped = time.perf_counter(), 0, False
        while steps < cfg["timesteps"]:
            if time_limit is not None and time.perf_counter() - start > time_limit:
                stopped = True
                break
            result = algo.train()
            steps = agent_steps(result)
            log.iteration(result, steps, time.perf_counter() - start, cfg)
            if val["every"] and steps >= next_val:
                next_val += val["every"]
                stats = validate(algo, cfg)
                log.validation(steps, stats)
                best = keep_best(algo, stats, best, out)
            if cfg["checkpoint_every"] and steps >= next_ckpt:
                next_ckpt += cfg["checkpoint_every"]
                algo.save_to_path(str(out / "checkpoints" / f"step_{steps}"))
        seconds = time.perf_counter() - start
        algo.save_to_path(str(out / "checkpoint"))
        final = validate(algo, cfg)
        log.validation(steps, final)
        keep_best(algo, final, best, out)
        nodes = algo.env_runner_group.foreach_env_runner(
            lambda runner: ray.get_runtime_context().get_node_id(), local_env_runner=False
        )
        summary = {
            "engine": "rllib",
            "agent_steps": steps,
            "seconds": round(seconds, 1),
            "agent_steps_per_second": round(steps / max(seconds, 1e-9), 1),
            "stopped_by_time_limit": stopped,
            "driver_node": ray.get_runtime_context().get_node_id(),
            "env_runner_nodes": nodes,
            "validation": final,
        }
        with open(out / "summary.json", "w") as f:
            json.dump(summary, f, indent=2)
        algo.stop()
        log.close()
        return summary
    finally:
        ray.shutdown()


def validate(algo: Any, cfg: dict[str, Any]) -> dict[str, float]:
    """Our protocol on the held-out validation seeds, with the shared module."""
    policy = module_policy(algo.get_module(SHARED))
    val = cfg["validation"]
    return summarize(run_episodes(cfg, policy, val["episodes"], val["seed"]))


def keep_best(
    algo: Any, stats: dict[str, float], best: tuple[float, float] | None, out: Path
) -> tuple[float, float]:
    """Save ``best_checkpoint/`` when the validation (success, then completion) improves."""
    score = validation_score(stats)
    if best is None or score > best:
        algo.save_to_path(str(out / "best_checkpoint"))
        return score
    return best


class Log:
    """``progress.csv`` (and TensorBoard events when ``tensorboard`` is installed), and
    ``validation.csv`` as the SB3 path writes it."""

    FIELDS = (
        "agent_steps",
        "seconds",
        "episode_return_mean",
        "success_rate",
        "completion_time",
        "cost",
        "infeasible_steps",
        "intervention",
        "eval/success_rate",
        "eval/completion_time",
        "eval/collisions",
    )

    def __init__(self, out: Path) -> None:
        self.out = out
        self.file = open(out / "progress.csv", "w", newline="")  # noqa: SIM115
        self.writer = csv.DictWriter(self.file, fieldnames=self.FIELDS)
        self.writer.writeheader()
        self.tb: Any = None  # TensorBoard's writer where it is installed
        try:
            from torch.utils.tensorboard import SummaryWriter

            self.tb = SummaryWriter(str(out))
        except ImportError:
            pass

    def write(self, row: dict[str, Any]) -> None:
        self.writer.writerow(row)
        self.file.flush()
        if self.tb is not None:
            for key, value in row.items():
                if key != "agent_steps" and value is not None and np.isfinite(value):
                    self.tb.add_scalar(key, value, row["agent_steps"])

    def iteration(self, result: dict, steps: int, seconds: float, cfg: dict) -> None:
        runners = result["env_runners"]
        rsvo = runners.get("rsvo", {})
        dt = float(cfg["env"].get("dt", 0.01))
        completion = rsvo.get("completion_steps")
        self.write(
            {
                "agent_steps": steps,
                "seconds": round(seconds, 2),
                "episode_return_mean": runners.get("episode_return_mean"),
                "success_rate": rsvo.get("success"),
                "completion_time": None if completion is None else completion * dt,
                "cost": rsvo.get("collision_steps"),
                "infeasible_steps": rsvo.get("infeasible"),
                "intervention": rsvo.get("intervention"),
            }
        )

    def validation(self, steps: int, stats: dict[str, float]) -> None:
        append_validation(self.out / "validation.csv", steps, stats)
        self.write(
            {
                "agent_steps": steps,
                "eval/success_rate": stats["success_rate"],
                "eval/completion_time": stats["completion_time"],
                "eval/collisions": stats["collisions"],
            }
        )

    def close(self) -> None:
        self.file.close()
        if self.tb is not None:
            self.tb.close()
