"""A parameter sweep on Ray Tune: weighting mode x theta assignment x seed, one table.

    python -m rsvo_env.training.sweep --engine rllib --scenario circular_swap \\
        --weightings asymmetric symmetric --thetas random paper --seeds 0 1 2 \\
        --timesteps 200000 --episodes 100 --out runs/sweep [--address HOST:PORT]

Each trial trains RLlib PPO (one shared module, the scenario's config) and evaluates it with
our protocol on the held-out seeds 1000, 1001, ...; on a cluster (``--address``) Tune spreads
the trials over its nodes. Writes ``sweep.csv`` and ``sweep.md`` in ``--out``. Theta
assignments: ``random`` (each episode draws theta from U(1, 10)), ``paper`` (the circular
game's 2, 1, 2, 1, ...), ``equal`` (every theta 1).
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path
from typing import Any

import numpy as np

from rsvo_env.training import config as configs
from rsvo_env.training import tune_runs
from rsvo_env.util.arguments import HelpFormatter, Parser, count
from rsvo_env.util.validation import shown

THETAS = ("random", "paper", "equal")


def with_theta(cfg: dict[str, Any], assignment: str) -> dict[str, Any]:
    """The config with one theta assignment."""
    env = dict(cfg["env"])
    n = int(env.get("num_agents", 6))
    env["theta_range"] = [1.0, 10.0] if assignment == "random" else None
    env["theta"] = [2.0 - (i % 2) for i in range(n)] if assignment == "paper" else None
    return {**cfg, "env": env}


def trial(params: dict[str, Any]) -> None:
    """One Tune trial: train, then evaluate on the held-out seeds; reports as it goes."""
    from ray import tune

    from rsvo_env.training.rllib_engine import SHARED, agent_steps, build, module_policy
    from rsvo_env.training.seeded_episodes import run_episodes, summarize

    cfg = params["cfg"]
    algo = build(cfg, 0, 1).build_algo()
    steps = 0
    while steps < cfg["timesteps"]:
        result = algo.train()
        steps = agent_steps(result)
        tune.report({"agent_steps": steps, "done_training": False})
    policy = module_policy(algo.get_module(SHARED))
    stats = summarize(run_episodes(cfg, policy, params["episodes"], params["eval_seed"]))
    algo.stop()
    tune.report({"agent_steps": steps, "done_training": True, **stats})


def main(argv: list[str] | None = None) -> int:
    p = Parser(
        prog="python -m rsvo_env.training.sweep",
        description=__doc__.split("\n\n")[0],
        formatter_class=HelpFormatter,
    )
    p.add_argument("--engine", choices=("rllib",), default="rllib")
    p.add_argument("--scenario", default="circular_swap")
    p.add_argument("--weightings", nargs="+", default=list(configs.WEIGHTINGS))
    p.add_argument("--thetas", nargs="+", default=["random", "paper"], choices=THETAS)
    p.add_argument("--seeds", nargs="+", type=count(0), default=[0, 1])
    p.add_argument("--timesteps", type=count(1), default=200_000, help="agent-steps a trial")
    p.add_argument("--episodes", type=count(1), default=100)
    p.add_argument("--eval-seed", type=count(0), default=1000)
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = tune_runs.parse(p, argv)
    try:
        base = configs.load(args.scenario)
        for assignment in args.set:
            configs.set_value(base, assignment)
        for w in args.weightings:
            if w not in configs.WEIGHTINGS:
                raise ValueError(f"--weightings {shown(w)}; use {configs.WEIGHTINGS}")
        grid = [
            configs.resolve(
                with_theta(base, theta),
                engine="rllib",
                weighting=w,
                seed=seed,
                timesteps=args.timesteps,
            )
            for w in args.weightings
            for theta in args.thetas
            for seed in args.seeds
        ]
    except (ValueError, TypeError) as err:
        p.exit(2, f"{p.prog}: error: {err}\n")
    rows = run_grid(grid, args)
    write(rows, Path(args.out), args)
    return 0


def trial_name(t: Any) -> str:
    """A short folder name (the default spells out the whole config)."""
    cfg = t.config["cfg"]
    return f"{cfg['weighting']}_{theta_name(cfg)}_seed{cfg['seed']}_{t.trial_id}"


def theta_name(cfg: dict[str, Any]) -> str:
    env = cfg["env"]
    return "random" if env.get("theta_range") else "paper" if env.get("theta") else "equal"


def run_grid(grid: list[dict[str, Any]], args: argparse.Namespace) -> list[dict[str, Any]]:
    from ray import tune

    results = tune_runs.fit(
        trial,
        {"cfg": tune.grid_search(grid), "episodes": args.episodes, "eval_seed": args.eval_seed},
        tune.TuneConfig(trial_dirname_creator=trial_name),
        "sweep",
        args.out,
        args.address,
    )
    rows = []
    for res in results:
        cfg, m = res.config["cfg"], res.metrics
        rows.append(
            {
                "weighting": cfg["weighting"],
                "theta": theta_name(cfg),
                "seed": cfg["seed"],
                "agent_steps": m["agent_steps"],
                **{k: m[k] for k in ("success_rate", "completion_time", "collisions")},
                "infeasible": m["infeasible"],
                "min_distance": m["min_distance"],
            }
        )
    rows.sort(key=lambda r: (r["weighting"], r["theta"], r["seed"]))
    return rows


def write(rows: list[dict[str, Any]], out: Path, args: argparse.Namespace) -> None:
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "sweep.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    lines = [
        f"# Sweep: {args.scenario}, weighting x theta x seed (RLlib PPO, residual actions)",
        "",
        f"{args.timesteps} agent-steps a trial; evaluation on {args.episodes} held-out seeds "
        f"from {args.eval_seed}, filter on.",
        "",
        "| weighting | theta | seeds | success | completion [s], mean ± SE over seeds | "
        "collisions | infeasible steps |",
        "|---|---|---|---|---|---|---|",
    ]
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault((r["weighting"], r["theta"]), []).append(r)
    for (w, theta), group in groups.items():
        times = np.array([r["completion_time"] for r in group], dtype=float)
        se = f"{times.std(ddof=1) / np.sqrt(len(times)):.3f}" if len(times) > 1 else "-"
        lines.append(
            f"| {w} | {theta} | {len(group)} | "
            f"{np.mean([r['success_rate'] for r in group]):.0%} | "
            f"{np.nanmean(times):.3f} ± {se} | {sum(r['collisions'] for r in group)} | "
            f"{sum(r['infeasible'] for r in group)} |"
        )
    (out / "sweep.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"written: {out / 'sweep.csv'}, {out / 'sweep.md'}")


if __name__ == "__main__":
    sys.exit(main())
