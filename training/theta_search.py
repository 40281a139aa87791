"""Search the fixed personalities that finish a scenario soonest: Ray Tune with Optuna's TPE.

    python -m rsvo_env.training.theta_search --scenario circular_swap --trials 200 \\
        --out runs/search_c6
    python -m rsvo_env.training.theta_search --scenario circular_swap --set num_agents=12 \\
        --trials 300 --out runs/search_c12 [--address HOST:PORT]

A trial is one theta vector (each agent's score log-uniform on [--low, --high]); its objective is
the mean completion step of the scripted controller behind the R-CBF filter over ``--seeds``, all
seeds in one batched env (``rsvo_env.training.personalities.evaluate``; an unfinished episode
counts twice the time cap). The circular game runs the paper's controller (``nominal=move_to_goal``)
unless ``--set nominal=...`` says otherwise. The search starts from the paper's alternating
assignment and from equal scores, so its answer is never worse than either. Trials run one at a time
by default, which makes the search a function of ``--search-seed`` (with concurrency, the sampler
sees results in the order they arrive). Writes ``search.json`` in ``--out``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.training import config as configs
from rsvo_env.training import tune_runs
from rsvo_env.training.personalities import FIELDS as STATS
from rsvo_env.training.personalities import PAPER_GAME, alternating, evaluate, objective
from rsvo_env.util.arguments import HelpFormatter, Parser, count
from rsvo_env.util.validation import check_positive, shown


def scenario_kwargs(scenario: str, assignments: list[str]) -> dict[str, Any]:
    """The env's keywords: the paper's controller for the circular game, then ``--set``."""
    kwargs = dict(PAPER_GAME) if scenario == "circular_swap" else {}
    for a in assignments:
        if "=" not in a:
            raise ValueError(f"--set {shown(a)}: use key=value, e.g. num_agents=12")
        key, raw = a.split("=", 1)
        kwargs[key] = configs.load_yaml(raw)
    return kwargs


def measure(theta: np.ndarray, params: dict[str, Any]) -> dict[str, Any]:
    """One assignment (N,) on the search's seeds: the objective and the means of every field."""
    stats = evaluate(theta[None], params["seeds"], params["scenario"], **params["kwargs"])
    out: dict[str, float | None] = {"completion": float(objective(stats, params["cap"])[0])}
    for key in STATS:
        out[key] = float(np.nanmean(stats[key])) if np.isfinite(stats[key]).any() else None
    return out


def trial(config: dict[str, Any]) -> None:
    from ray import tune

    params = config["params"]
    theta = np.array([config[f"theta_{i}"] for i in range(params["n"])])
    tune.report(measure(theta, params))


def search(params: dict[str, Any], args: argparse.Namespace) -> list[dict[str, Any]]:
    """Every trial's theta and measures, in the order they ran."""
    import optuna
    from ray import tune
    from ray.tune.search.optuna import OptunaSearch

    n = params["n"]
    names = [f"theta_{i}" for i in range(n)]
    starts = [dict(zip(names, alternating(n), strict=True)), dict.fromkeys(names, 1.0)]
    searcher = OptunaSearch(
        metric="completion",
        mode="min",
        sampler=optuna.samplers.TPESampler(seed=args.search_seed),
        points_to_evaluate=starts,
    )
    space: dict[str, Any] = {name: tune.loguniform(args.low, args.high) for name in names}
    results = tune_runs.fit(
        trial,
        {**space, "params": params},
        tune.TuneConfig(
            search_alg=searcher,
            num_samples=args.trials,
            max_concurrent_trials=args.concurrency,
            reuse_actors=True,  # one worker, its compiled kernels loaded once
            trial_dirname_creator=lambda t: f"trial_{t.trial_id}",
        ),
        "theta_search",
        args.out,
        args.address,
    )
    rows = []
    for res in results:
        theta = [float(res.config[name]) for name in names]
        keys = ("completion", *STATS)
        rows.append({"theta": theta, **{k: res.metrics[k] for k in keys}})
    return rows


def main(argv: list[str] | None = None) -> int:
    p = Parser(
        prog="python -m rsvo_env.training.theta_search",
        description=__doc__.split("\n\n")[0],
        formatter_class=HelpFormatter,
    )
    p.add_argument("--scenario", default="circular_swap")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    p.add_argument("--seeds", nargs="+", type=count(0), default=[0])
    p.add_argument("--trials", type=count(1), default=200)
    p.add_argument("--low", type=float, default=0.1, help="smallest theta searched")
    p.add_argument("--high", type=float, default=10.0, help="largest theta searched")
    p.add_argument("--search-seed", type=count(0), default=0)
    p.add_argument("--concurrency", type=count(1), default=1)
    args = tune_runs.parse(p, argv)
    try:
        low, high = check_positive(args.low, "--low"), check_positive(args.high, "--high")
        if low > high:
            raise ValueError(f"--low {low} exceeds --high {high}")
        kwargs = scenario_kwargs(args.scenario, args.set)
        # built once here, so that a bad keyword fails now, by name, and not inside a trial
        probe = BatchedEnv(args.scenario, **kwargs)
    except (ValueError, TypeError) as err:
        p.exit(2, f"{p.prog}: error: {err}\n")
    n, cap = probe.num_agents, probe.sim.max_steps
    params = {"scenario": args.scenario, "kwargs": kwargs, "seeds": args.seeds, "n": n, "cap": cap}
    rows = search(params, args)
    best = min(rows, key=lambda r: r["completion"])
    report = {
        "scenario": args.scenario,
        "kwargs": kwargs,
        "seeds": args.seeds,
        "range": [low, high],
        "trials": len(rows),
        "sampler": f"optuna TPE, seed {args.search_seed}",
        "best": best,
        "alternating": {"theta": alternating(n), **measure(np.array(alternating(n)), params)},
        "equal": {"theta": [1.0] * n, **measure(np.ones(n), params)},
        "rows": rows,
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "search.json").write_text(json.dumps(report, indent=1))
    print(
        f"{len(rows)} trials; best mean completion {best['completion']:.1f} steps with theta "
        f"{np.round(best['theta'], 3).tolist()}; alternating "
        f"{report['alternating']['completion']:.1f}, equal {report['equal']['completion']:.1f}"
    )
    print(f"written: {out / 'search.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
