"""Safety filter against constrained RL: four methods on two scenarios, as safe-RL papers report
them; writes benchmarks/results/safe_rl.md and safe_rl.png.

    python -m benchmarks.studies.safe_rl --train --runs runs/safe_rl  # trains the missing, reports
    python -m benchmarks.studies.safe_rl --runs runs/safe_rl          # reports on runs made before

The methods, on the paper's circular game (6 agents) and the crowd of 12, each from its config in
``training/configs`` with the same budget of agent-steps and 3 training seeds:

* ``scripted``: the config's scripted controller behind the R-CBF filter (no training);
* ``filtered residual``: PPO's residual on the scripted command behind the filter (the config);
* ``PPO``: the same policy and task without the filter (``env.safety_filter=false``);
* ``PPO-Lagrangian``: the same without the filter, under the cost constraint
  (``algo=ppo_lagrangian``, ``training/lagrangian.py``).

Each run's final ``model.zip`` (no selection on validation) is evaluated deterministically on
100 held-out seeds 1000..1099, the scripted controller on the same seeds; the unfiltered runs
are evaluated unfiltered, as they were trained. Cost: an agent's steps in contact (OmniSafe's
EpCost, per agent); in training, every agent-step in contact of the run.
"""

from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from benchmarks.harness import RESULTS, ROOT
from rsvo_env.training import config as configs
from rsvo_env.training.config import limit_threads
from rsvo_env.training.evaluate import load_model
from rsvo_env.training.seeded_episodes import run_episodes, scripted_policy, summarize

EPISODES, SEED, SEEDS = 100, 1000, (0, 1, 2)
# the agent-steps of every trained run of a scenario (the same for every method)
BUDGET = {"circular_swap": 3_000_000, "crowd": 6_000_000}
METHODS = {
    "scripted": ("scripted (filter)", None),
    "residual": ("filtered residual (PPO)", []),
    "ppo": ("PPO, no filter", ["env.safety_filter=false"]),
    "ppo_lagrangian": (
        "PPO-Lagrangian, no filter",
        ["algo=ppo_lagrangian", "env.safety_filter=false"],
    ),
}


def command(scenario: str, method: str, seed: int, out: Path) -> list[str]:
    sets = [a for s in METHODS[method][1] for a in ("--set", s)]
    return [
        sys.executable,
        "-m",
        "rsvo_env.training.train",
        "--scenario",
        scenario,
        *sets,
        "--timesteps",
        str(BUDGET[scenario]),
        "--seed",
        str(seed),
        "--no-progress",
        "--out",
        str(out),
    ]


def seeds_of(method: str) -> tuple[int, ...]:
    """The training seeds of a method (the scripted controller: one evaluation)."""
    return SEEDS if METHODS[method][1] is not None else (0,)


def run_dir(runs: Path, scenario: str, method: str, seed: int) -> Path:
    return runs / f"{scenario}_{method}_s{seed}"


def train_missing(runs: Path, jobs: int) -> None:
    todo = [
        (s, m, seed)
        for s in BUDGET
        for m in METHODS
        if METHODS[m][1] is not None
        for seed in SEEDS
        if not (run_dir(runs, s, m, seed) / "summary.json").exists()
    ]

    def one(job: tuple[str, str, int]) -> None:
        out = run_dir(runs, *job)
        log = runs / f"{out.name}.log"
        with open(log, "w") as f:
            cmd = command(*job, out)
            print(" ".join(cmd[1:]), flush=True)
            subprocess.run(cmd, cwd=ROOT, stdout=f, stderr=subprocess.STDOUT, check=True)

    runs.mkdir(parents=True, exist_ok=True)
    with ThreadPoolExecutor(jobs) as pool:
        list(pool.map(one, todo))


def progress(run: Path) -> dict[str, np.ndarray]:
    """Training curves from SB3's progress.csv: agent-steps, return and cost per agent-episode,
    and the contacts so far."""
    with open(run / "progress.csv") as f:
        rows = [r for r in csv.DictReader(f) if r.get("rollout/episode_cost")]
    keys = {
        "steps": "time/total_timesteps",
        "return": "rollout/return",
        "cost": "rollout/episode_cost",
        "contacts": "rollout/contact_agent_steps",
    }
    return {k: np.array([float(r[v]) for r in rows]) for k, v in keys.items()}


def evaluate(runs: Path, scenario: str, method: str, seed: int) -> dict:
    if METHODS[method][1] is None:
        cfg = configs.resolve(configs.load(scenario))
        return summarize(run_episodes(cfg, scripted_policy, EPISODES, SEED, action="direct"))
    run = run_dir(runs, scenario, method, seed)
    policy, cfg = load_model(run / "model.zip")
    stats = summarize(run_episodes(cfg, policy, EPISODES, SEED))
    curve = progress(run)
    summary = json.loads((run / "summary.json").read_text())
    stats.update(
        train_contacts=float(curve["contacts"][-1]),
        train_cost_final=float(curve["cost"][-1]),
        train_steps=summary["agent_steps"],
        train_seconds=summary["seconds"],
    )
    return stats


def spread(values: list[float], digits: int = 2, percent: bool = False) -> str:
    v = np.array(values, dtype=float) * (100 if percent else 1)
    unit = " %" if percent else ""
    if len(v) == 1:
        return f"{v[0]:.{digits}f}{unit}"
    return f"{np.nanmean(v):.{digits}f} ± {np.nanstd(v):.{digits}f}{unit}"


def table(results: dict) -> list[str]:
    lines = [
        "| scenario | method | success | completion [s] | episode return | episode cost, "
        "evaluation | contact agent-steps, training | episode cost, end of training | "
        "trained |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for (scenario, method), seeds in results.items():

        def get(key: str, seeds: list[dict] = seeds) -> list[float]:
            return [s[key] for s in seeds]

        trained = "-"
        if "train_steps" in seeds[0]:
            steps, seconds = np.mean(get("train_steps")), np.mean(get("train_seconds"))
            trained = f"{steps / 1e6:.1f} M in {seconds:.0f} s"
        lines.append(
            f"| {scenario} | {METHODS[method][0]} | {spread(get('success_rate'), 0, True)} | "
            f"{spread(get('completion_time'))} | {spread(get('episode_return'))} | "
            f"{spread(get('episode_cost'), 3)} | "
            + (
                f"{spread(get('train_contacts'), 0)} | {spread(get('train_cost_final'), 3)} | "
                if "train_contacts" in seeds[0]
                else "- | - | "
            )
            + f"{trained} |"
        )
    return lines


SMOOTH = 10  # updates a running mean of a training curve spans


def smooth(values: np.ndarray) -> np.ndarray:
    """A running mean over the last SMOOTH values (fewer at the start)."""
    total = np.cumsum(values)
    out = total.copy()
    out[SMOOTH:] = total[SMOOTH:] - total[:-SMOOTH]
    return out / np.minimum(np.arange(1, len(values) + 1), SMOOTH)


def plot(runs: Path, results: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenarios = list(BUDGET)
    fig, axes = plt.subplots(len(scenarios), 2, figsize=(11, 4.2 * len(scenarios)))
    colors = {"scripted": "0.4", "residual": "C0", "ppo": "C3", "ppo_lagrangian": "C2"}
    for row, scenario in zip(axes, scenarios, strict=True):
        for method, (label, sets) in METHODS.items():
            if sets is None:
                stats = results[(scenario, method)][0]
                for ax, key in zip(row, ("episode_return", "episode_cost"), strict=True):
                    ax.axhline(stats[key], color=colors[method], ls="--", label=f"{label}, eval")
                continue
            curves = [progress(run_dir(runs, scenario, method, s)) for s in SEEDS]
            n = min(len(c["steps"]) for c in curves)
            steps = curves[0]["steps"][:n] / 1e6
            for ax, key in zip(row, ("return", "cost"), strict=True):
                values = np.stack([smooth(c[key][:n]) for c in curves])
                ax.plot(steps, values.mean(axis=0), color=colors[method], label=label)
                low, high = values.min(axis=0), values.max(axis=0)
                ax.fill_between(steps, low, high, color=colors[method], alpha=0.2)
        row[0].set_title(f"{scenario}: episode return of an agent (training)")
        row[1].set_title(f"{scenario}: episode cost of an agent (steps in contact)")
        row[1].set_yscale("symlog", linthresh=0.1)
        for ax in row:
            ax.set_xlabel("agent-steps [M]")
            ax.grid(alpha=0.3)
        row[1].legend(fontsize=8)
    fig.suptitle(
        f"Training: each seed a running mean over {SMOOTH} updates\n"
        "line: the mean of 3 seeds; band: the lowest to the highest seed"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def findings(results: dict) -> list[str]:
    """What the table shows: its numbers in sentences, then what they mean."""
    out = [
        "The filter's zero is a property, not a rate: the filtered runs never touched, in "
        "training or at evaluation, in any seed. A Lagrangian constrains the *mean* cost to a "
        "budget (`cost_limit`, 1 contact step per agent-episode here): it settles near that "
        "budget, pays for it with contacts all through training while its multiplier climbs, and "
        "does not reach zero. Unconstrained PPO ignores contacts and drives through its "
        "neighbours, which is why it is fastest. Where the task is hard (the crowd), the "
        "constraint also costs the Lagrangian its success, while the filtered residual keeps both.",
        "",
    ]
    for scenario in BUDGET:
        r = {m: results[(scenario, m)] for m in METHODS}

        def mean(m: str, k: str, r: dict = r) -> float:
            return float(np.nanmean([s[k] for s in r[m]]))

        filtered_cost = sum(s["episode_cost"] for m in ("scripted", "residual") for s in r[m])
        filtered_train = sum(s["train_contacts"] for s in r["residual"])
        out.append(
            f"- **{scenario}.** Behind the filter the cost is {filtered_cost:g} at evaluation "
            f"(scripted and residual, every seed) and {filtered_train:g} contact agent-steps in "
            f"training. Unfiltered PPO: episode cost {mean('ppo', 'episode_cost'):.3f} at "
            f"evaluation, {mean('ppo', 'train_contacts'):,.0f} contact agent-steps in training; "
            f"PPO-Lagrangian: {mean('ppo_lagrangian', 'episode_cost'):.3f} and "
            f"{mean('ppo_lagrangian', 'train_contacts'):,.0f}. Success: scripted "
            f"{mean('scripted', 'success_rate'):.0%}, filtered residual "
            f"{mean('residual', 'success_rate'):.0%}, PPO {mean('ppo', 'success_rate'):.0%}, "
            f"PPO-Lagrangian {mean('ppo_lagrangian', 'success_rate'):.0%}; completion "
            f"{mean('residual', 'completion_time'):.2f} s (filtered residual) against "
            f"{mean('ppo', 'completion_time'):.2f} s (PPO) and "
            f"{mean('ppo_lagrangian', 'completion_time'):.2f} s (PPO-Lagrangian)."
        )
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--runs", default="runs/safe_rl", help="the run directories")
    p.add_argument("--train", action="store_true", help="train the runs that are missing first")
    p.add_argument("--jobs", type=int, default=2, help="training runs at a time")
    p.add_argument("--out", default=str(RESULTS / "safe_rl.md"))
    p.add_argument("--plot-only", action="store_true", help="redraw the PNG from the JSON")
    args = p.parse_args(argv)
    runs = Path(args.runs)
    out = Path(args.out)
    if args.plot_only:
        saved = json.loads(out.with_suffix(".json").read_text())
        results = {tuple(k.split("/")): v for k, v in saved.items()}
        plot(runs, results, out.with_suffix(".png"))
        return 0
    if args.train:
        train_missing(runs, args.jobs)
    limit_threads(1)
    results = {
        (s, m): [evaluate(runs, s, m, seed) for seed in seeds_of(m)]
        for s in BUDGET
        for m in METHODS
    }
    png = out.with_suffix(".png")
    plot(runs, results, png)
    commands = [
        " ".join(["python", *command(s, m, seed, run_dir(runs, s, m, seed))[1:]])
        for s in BUDGET
        for m in METHODS
        if METHODS[m][1] is not None
        for seed in SEEDS
    ]
    text = [
        "# Safety filter against constrained RL",
        "",
        f"Written by `python -m benchmarks.studies.safe_rl --train --runs {args.runs}` "
        "(the module's docstring says what each method is). Every trained run has the same "
        "budget of agent-steps per scenario, 3 training seeds (0, 1, 2); its final model is "
        f"evaluated deterministically on {EPISODES} held-out seeds {SEED}..{SEED + EPISODES - 1}, "
        "the scripted controller on the same seeds. Success: every agent at its goal within the "
        "evaluation cap; completion: over the successful episodes; episode return and cost: "
        "an agent's, averaged over agents and episodes (OmniSafe's EpRet and EpCost; a step in "
        "contact costs 1); contact agent-steps, training: every agent-step in contact during "
        "the run. Mean ± standard deviation over the 3 training seeds.",
        "",
        *table(results),
        "",
        "## What it shows",
        "",
        *findings(results),
        "",
        f"![training curves]({png.name})",
        "",
        "## Commands",
        "",
        "```bash",
        *commands,
        "```",
        "",
    ]
    out.write_text("\n".join(text))
    with open(out.with_suffix(".json"), "w") as f:
        json.dump({f"{s}/{m}": v for (s, m), v in results.items()}, f, indent=1)
    print(f"wrote {out} and {png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
