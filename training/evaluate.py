"""Evaluate a trained model (with the config saved beside it) on seeded episodes, filter on.

    python -m rsvo_env.training.evaluate runs/circular/model.zip --episodes 100 --seed 1000 \\
        --compare-scripted --gif runs/circular/episode.gif
    python -m rsvo_env.training.evaluate runs/crowd/best_model.zip --set env.num_agents=100

``--set`` overrides the saved config for the evaluation alone (as ``rsvo_env.training.train --set``
does for training): the observation is local, so a policy trained on 12 agents runs unchanged
in a crowd of 100 or 1,000.

Prints and saves (``evaluation.json`` beside the model, or ``--out``) the success rate, mean
completion time, collisions, infeasible steps and mean intervention. ``--compare-scripted`` runs
the scripted controller under the same protocol (same seeds, dt, speed limit, filter and time
cap) and reports the paired difference of completion times with its standard error.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rsvo_env.training import config as configs
from rsvo_env.training.algorithms import algorithm_class
from rsvo_env.training.config import make_env
from rsvo_env.training.seeded_episodes import (
    evaluation_cap,
    model_policy,
    paired,
    record_gif,
    run_episodes,
    scripted_policy,
    summarize,
)
from rsvo_env.util.arguments import HelpFormatter, Parser, count, output_problem
from rsvo_env.util.validation import shown


def load_model(path: str | Path, overrides: Sequence[str] = ()) -> tuple[Any, dict[str, Any]]:
    """The policy of a trained model and the resolved config saved beside it (``config.yaml``
    in its run directory, or in the directory above for a checkpoint), with ``overrides``
    (``KEY=VALUE``, as ``--set``) applied. ``path``: an SB3 ``.zip``, or an RLlib checkpoint
    directory written by ``--engine rllib``."""
    path = Path(path)
    if not path.exists():
        raise ValueError(f"model {shown(str(path))} does not exist")
    for folder in (path.parent, path.parent.parent):
        if (folder / "config.yaml").exists():
            cfg = configs.load(path=folder / "config.yaml")
            for assignment in overrides:
                configs.set_value(cfg, assignment)
            cfg = configs.resolve(cfg)
            break
    else:
        raise ValueError(
            f"no config.yaml beside {shown(str(path))}: was it written by rsvo_env.training.train?"
        )
    if (path / "learner_group").is_dir():
        from rsvo_env.training.rllib_engine import load_module, module_policy

        return module_policy(load_module(path)), cfg

    algo = algorithm_class(cfg["algo"])
    return model_policy(algo.load(path, device="cpu")), cfg


def describe(name: str, stats: dict[str, float]) -> str:
    return (
        f"{name:>9}: success {stats['success_rate']:.0%}, completion "
        f"{stats['completion_time']:.3f} s, collisions {stats['collisions']}, infeasible steps "
        f"{stats['infeasible']}, intervention {stats['intervention']:.3f} m/s "
        f"(rate {stats['intervention_rate']:.2f}), smallest distance {stats['min_distance']:.4f}"
    )


def evaluate(
    model_path: str | Path,
    episodes: int,
    seed: int,
    compare_scripted: bool = False,
    gif: str | None = None,
    weighting: str | None = None,
) -> dict[str, Any]:
    """The evaluation as a dict (what ``evaluation.json`` holds)."""
    return evaluate_loaded(
        *load_model(model_path), model_path, episodes, seed, compare_scripted, gif, weighting
    )


def evaluate_loaded(
    policy: Any,
    cfg: dict[str, Any],
    model_path: str | Path,
    episodes: int,
    seed: int,
    compare_scripted: bool = False,
    gif: str | None = None,
    weighting: str | None = None,
) -> dict[str, Any]:
    """``evaluate`` of a policy and config already loaded (``load_model``)."""
    configs.limit_threads(cfg["threads"])
    learned = run_episodes(cfg, policy, episodes, seed, weighting=weighting)
    result: dict[str, Any] = {
        "model": str(model_path),
        "episodes": episodes,
        "seed": seed,
        "weighting": weighting or cfg["weighting"],
        "max_steps": evaluation_cap(cfg),
        "num_agents": make_env(cfg, num_envs=1).num_agents,
        "policy": summarize(learned),
    }
    if compare_scripted:
        scripted = run_episodes(cfg, scripted_policy, episodes, seed, "direct", weighting)
        result["scripted"] = summarize(scripted)
        result["paired_completion_time"] = paired(learned, scripted)
    if gif:
        result["gif"] = record_gif(cfg, policy, seed, gif, fps=round(1 / cfg["env"]["dt"]))
    return result


def main(argv: list[str] | None = None, prog: str = "python -m rsvo_env.training.evaluate") -> int:
    p = Parser(
        prog=prog,
        description=__doc__.split("\n\n")[0],
        formatter_class=HelpFormatter,
    )
    p.add_argument("model", help="a model.zip (SB3) or checkpoint directory (RLlib) of a run")
    p.add_argument("--episodes", type=count(1), default=100)
    p.add_argument("--seed", type=count(0), default=1000, help="episode k is seeded seed + k")
    p.add_argument("--compare-scripted", action="store_true")
    p.add_argument("--weighting", choices=configs.WEIGHTINGS, help="default: the config's")
    p.add_argument("--gif", help="write the first episode as a GIF here")
    p.add_argument("--out", help="the JSON report (default: evaluation.json beside the model)")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override an entry of the saved config, e.g. --set env.num_agents=100",
    )
    args = p.parse_args(argv)
    out = Path(args.out) if args.out else Path(args.model).parent / "evaluation.json"
    # the user's mistakes, found before any episode runs; what fails after is a bug
    problem = output_problem(out, ".json") or (args.gif and output_problem(Path(args.gif), ".gif"))
    if problem:
        p.exit(2, f"{p.prog}: error: {problem}\n")
    try:
        policy, cfg = load_model(args.model, args.set)
    except ValueError as err:
        p.exit(2, f"{p.prog}: error: {err}\n")
    result = evaluate_loaded(
        policy,
        cfg,
        args.model,
        args.episodes,
        args.seed,
        args.compare_scripted,
        args.gif,
        args.weighting,
    )
    print(
        f"{args.episodes} episodes, seeds {args.seed}..{args.seed + args.episodes - 1}, "
        f"each capped at {result['max_steps']} steps"
    )
    print(describe("policy", result["policy"]))
    if args.compare_scripted:
        print(describe("scripted", result["scripted"]))
        d = result["paired_completion_time"]
        print(
            f"   paired: policy - scripted completion = {d['mean_difference']:+.3f} s "
            f"+- {d['standard_error']:.3f} (SE) over {d['paired_seeds']} seeds both finish; "
            f"{d['relative_change']:+.1%} +- {d['relative_standard_error']:.1%}"
        )
    if args.gif:
        print(f"GIF: {result['gif']}")
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out, "w") as f:
        json.dump(result, f, indent=2)
    print(f"report: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
