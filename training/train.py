"""Train a nominal policy behind the R-CBF safety filter with Stable-Baselines3.

    python -m rsvo_env.training.train --scenario circular_swap --algo ppo --timesteps 6000000 \\
        --seed 0 --weighting asymmetric --action residual --out runs/circular \\
        --time-limit 600

Every agent of every env is one slot of a shared policy (``rsvo_env.wrappers.SB3VecEnv`` over a
``BatchedEnv``). The run directory gets ``config.yaml`` (the resolved config, written first),
``progress.csv`` and TensorBoard logs (``tb/``), ``validation.csv``, ``checkpoints/``,
``best_model.zip``, and at the end ``model.zip`` and ``summary.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

from rsvo_env.training import config as configs
from rsvo_env.training.algorithms import algorithm_class
from rsvo_env.util.arguments import HelpFormatter, Parser, count, output_problem

# flags of the RLlib engine alone: given with another engine they would be ignored
RLLIB_FLAGS = ("num_env_runners", "num_envs_per_env_runner", "address")


def parser(prog: str = "python -m rsvo_env.training.train") -> argparse.ArgumentParser:
    p = Parser(
        prog=prog,
        description=__doc__.split("\n\n")[0],
        formatter_class=HelpFormatter,
    )
    p.add_argument("--scenario", default="circular_swap", help="its config: training/configs/")
    p.add_argument("--config", help="a config file instead of the scenario's")
    p.add_argument("--algo", choices=configs.ALGOS, help="default: the config's")
    p.add_argument("--action", choices=configs.ACTIONS, help="default: the config's")
    p.add_argument("--weighting", choices=configs.WEIGHTINGS, help="default: the config's")
    p.add_argument("--timesteps", type=int, help="agent-steps (default: the config's)")
    p.add_argument("--num-envs", type=int, help="envs stepped together (default: the config's)")
    p.add_argument("--seed", type=count(0), help="seeds the policy, the sampling and the envs")
    p.add_argument("--threads", type=int, help="torch threads (default 1: fastest on few cores)")
    p.add_argument("--time-limit", type=float, help="stop after this many seconds and save")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override any config entry, e.g. --set env.num_agents=8 --set ppo.n_epochs=10",
    )
    p.add_argument(
        "--engine", choices=configs.ENGINES, help="sb3 (default) or rllib (the distributed extra)"
    )
    p.add_argument("--num-env-runners", type=count(0), help="rllib: sampling processes (0)")
    p.add_argument("--num-envs-per-env-runner", type=count(1), help="rllib: envs each (1)")
    p.add_argument("--address", help="rllib: a running Ray cluster (default: a local instance)")
    p.add_argument("--out", required=True, help="the run directory")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--verbose", action="store_true", help="print SB3's log tables")
    return p


def build_config(args: argparse.Namespace) -> dict[str, Any]:
    cfg = configs.load(None if args.config else args.scenario, args.config)
    for assignment in args.set:
        configs.set_value(cfg, assignment)
    return configs.resolve(
        cfg,
        algo=args.algo,
        action=args.action,
        weighting=args.weighting,
        timesteps=args.timesteps,
        num_envs=args.num_envs,
        seed=args.seed,
        threads=args.threads,
        engine=args.engine,
    )


def train(
    cfg: dict[str, Any],
    out: str | Path,
    time_limit: float | None = None,
    progress: bool = True,
    verbose: bool = False,
) -> dict[str, Any]:
    """Train as ``cfg`` says into ``out``; returns the run's summary (also in summary.json)."""
    from stable_baselines3.common.callbacks import CallbackList, CheckpointCallback
    from stable_baselines3.common.logger import configure
    from stable_baselines3.common.vec_env import VecMonitor

    from rsvo_env.training.callbacks import EpisodeStats, Progress, TimeLimit, Validation
    from rsvo_env.wrappers.sb3 import SB3VecEnv

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    configs.save(cfg, out / "config.yaml")
    configs.limit_threads(cfg["threads"])
    batched = configs.make_env(cfg, num_envs=cfg["num_envs"])
    venv = VecMonitor(SB3VecEnv(batched))
    algo = algorithm_class(cfg["algo"])
    hyper = configs.hyperparameters(cfg)
    if cfg["algo"] == "ppo_lagrangian":
        hyper["multiplier_log"] = str(out / "lagrangian.csv")
    model = algo("MlpPolicy", venv, seed=cfg["seed"], verbose=0, **hyper)
    model.set_logger(configure(str(out), ["csv", "tensorboard"] + (["stdout"] if verbose else [])))
    slots = venv.num_envs
    limit = TimeLimit(time_limit)
    validation = Validation(cfg, out)
    callbacks = [
        EpisodeStats(batched.num_agents, batched.scenario.u_max, batched.scenario.params["dt"]),
        validation,
        limit,
    ]
    if progress:
        callbacks.append(Progress(cfg["timesteps"], time_limit))
    if cfg["checkpoint_every"]:
        every = max(cfg["checkpoint_every"] // slots, 1)
        callbacks.append(CheckpointCallback(every, str(out / "checkpoints"), name_prefix="model"))
    start = time.perf_counter()
    model.learn(cfg["timesteps"], callback=CallbackList(callbacks))
    seconds = time.perf_counter() - start
    model.save(out / "model.zip")
    final = validation.validate()
    validation.logger.dump(model.num_timesteps)
    model.logger.close()  # its CSV and TensorBoard files, closed here, not left to the collector
    summary = {
        "agent_steps": int(model.num_timesteps),
        "seconds": round(seconds, 1),
        "agent_steps_per_second": round(model.num_timesteps / seconds, 1),
        "stopped_by_time_limit": limit.hit,
        "validation": final,
    }
    with open(out / "summary.json", "w") as f:
        json.dump(summary, f, indent=2)
    return summary


def main(argv: list[str] | None = None, prog: str = "python -m rsvo_env.training.train") -> int:
    p = parser(prog)
    args = p.parse_args(argv)
    try:
        cfg = build_config(args)
    except (ValueError, TypeError) as err:
        p.exit(2, f"{p.prog}: error: {err}\n")
    if args.time_limit is not None and not args.time_limit > 0:
        p.exit(2, f"{p.prog}: error: --time-limit = {args.time_limit} must be > 0\n")
    problem = output_problem(Path(args.out), directory=True)
    if problem:
        p.exit(2, f"{p.prog}: error: --out {problem}\n")
    rllib_only = [f for f in RLLIB_FLAGS if getattr(args, f) is not None]
    if cfg["engine"] != "rllib" and rllib_only:
        flags = ", ".join("--" + f.replace("_", "-") for f in rllib_only)
        p.exit(2, f"{p.prog}: error: {flags} are for --engine rllib, not {cfg['engine']}\n")
    if cfg["engine"] == "rllib":
        from rsvo_env.training.rllib_engine import train_rllib

        summary = train_rllib(
            cfg,
            args.out,
            args.time_limit,
            args.num_env_runners or 0,
            args.num_envs_per_env_runner or 1,
            args.address,
        )
    else:
        summary = train(cfg, args.out, args.time_limit, not args.no_progress, args.verbose)
    val = summary["validation"]
    stop = " (time limit)" if summary["stopped_by_time_limit"] else ""
    print(
        f"trained {summary['agent_steps']} agent-steps in {summary['seconds']} s{stop}, "
        f"{summary['agent_steps_per_second']:.0f} agent-steps/s"
    )
    print(
        f"validation on {val['episodes']} held-out seeds: success {val['success_rate']:.0%}, "
        f"completion {val['completion_time']:.2f} s, collisions {val['collisions']}, "
        f"infeasible steps {val['infeasible']}"
    )
    model = "checkpoint" if cfg["engine"] == "rllib" else "model.zip"
    print(f"model and config: {Path(args.out) / model}, {Path(args.out) / 'config.yaml'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
