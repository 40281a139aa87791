"""Evaluate the training runs of issue-level experiments and write benchmarks/results/training.md.

The runs are made first with the commands printed in the report (``RUNS`` below, each a plain
``python -m rsvo_env.training.train`` call); this script evaluates each run's ``best_model.zip``
(chosen on the validation seeds 900000+) on 100 held-out seeds 1000..1099 against the scripted
controller, and embeds ``training_speed.md`` (``benchmarks/speed/training_speed.py``).

    python -m benchmarks.reports.training_results --runs runs
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

import numpy as np

from benchmarks.harness import RESULTS
from rsvo_env.training.config import limit_threads
from rsvo_env.training.evaluate import load_model
from rsvo_env.training.seeded_episodes import (
    evaluation_cap,
    paired,
    run_episodes,
    scripted_policy,
    summarize,
)

EPISODES, SEED = 100, 1000
GIF = "learned_circular.gif"
TRAIN = "python -m rsvo_env.training.train"
RUNS = {
    "circular_residual": f"{TRAIN} --scenario circular_swap --action residual --seed 0 "
    "--time-limit 600 --out runs/circular_residual",
    "circular_direct": f"{TRAIN} --scenario circular_swap --action direct --seed 0 "
    "--time-limit 600 --out runs/circular_direct",
    **{
        f"weighting_{w}_s{s}": f"{TRAIN} --scenario circular_swap --weighting {w} --seed {s} "
        f"--timesteps 3000000 --out runs/weighting_{w}_s{s}"
        for w in ("asymmetric", "symmetric")
        for s in (0, 1, 2)
    },
}
# the crowd config and what it is without each of its parts: (overrides, training seeds, meaning);
# the parts were tried with the validation of 100 episodes of 40 s the config had then (training
# episodes are 40 s either way)
OLD_VALIDATION = "--set validation.max_steps=null --set validation.episodes=100"
NO_CLOCK, NO_INTERACTION = "--set env.stall_clock=null", "--set interaction_radius=null"
CROWD = {
    "crowd": ("", (0, 1, 2), "the config: yielding, interaction radius, stall clock"),
    "crowd_no_clock": (f"{OLD_VALIDATION} {NO_CLOCK}", (0, 1), "without the stall clock"),
    "crowd_no_interaction": (
        f"{OLD_VALIDATION} {NO_INTERACTION}",
        (0, 1),
        "without the interaction radius",
    ),
    "crowd_yield_only": (
        f"{OLD_VALIDATION} {NO_INTERACTION} {NO_CLOCK}",
        (0, 1, 2),
        "yielding alone",
    ),
}
RUNS.update(
    {
        f"{name}_s{s}": " ".join(
            [f"{TRAIN} --scenario crowd", *sets.split(), f"--seed {s} --out runs/{name}_s{s}"]
        )
        for name, (sets, seeds, _) in CROWD.items()
        for s in seeds
    }
)
# the plain gate: a parked agent never steps aside
PLAIN_GATE = (
    f"{OLD_VALIDATION} --set yield_radius=null {NO_INTERACTION} {NO_CLOCK} --timesteps 6000000"
)
RUNS["crowd_plain_gate"] = (
    f"{TRAIN} --scenario crowd {PLAIN_GATE} --seed 0 --out runs/crowd_plain_gate"
)
# every crowd run is evaluated with both time caps (steps), the scripted controller too
CROWD_CAPS = (400, 1000)


def evaluate(run: Path) -> dict:
    policy, cfg = load_model(run / "best_model.zip")
    learned = run_episodes(cfg, policy, EPISODES, SEED)
    scripted = run_episodes(cfg, scripted_policy, EPISODES, SEED, "direct")
    summary = json.loads((run / "summary.json").read_text())
    return {
        "cfg": cfg,
        "policy": summarize(learned),
        "scripted": summarize(scripted),
        "paired": paired(learned, scripted),
        "summary": summary,
        "training_collisions": training_collisions(run),
    }


def training_collisions(run: Path) -> int:
    """Collision steps over the whole training run (the last logged running total)."""
    with open(run / "progress.csv") as f:
        totals = [r["rollout/collision_steps_total"] for r in csv.DictReader(f)]
    return int(float([t for t in totals if t][-1]))


def row(name: str, r: dict) -> str:
    p, s, d, t = r["policy"], r["scripted"], r["paired"], r["summary"]
    return (
        f"| {name} | {t['agent_steps'] / 1e6:.1f} M in {t['seconds']:.0f} s | "
        f"{r['training_collisions']} | {p['success_rate']:.0%} | {s['success_rate']:.0%} | "
        f"{p['completion_time']:.3f} | {s['completion_time']:.3f} | "
        f"{d['mean_difference']:+.3f} ± {d['standard_error']:.3f} ({d['relative_change']:+.1%}) | "
        f"{p['collisions']} / {s['collisions']} | {p['infeasible']} | {p['intervention']:.3f} |"
    )


HEADER = [
    "| run | trained | collisions in training | success | scripted success | completion [s] "
    "| scripted [s] | paired difference ± SE (relative) | collisions policy / scripted "
    "| infeasible steps | mean intervention [m/s] |",
    "|---|---|---|---|---|---|---|---|---|---|---|",
]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--runs", default="runs", help="the folder holding the runs")
    args = p.parse_args()
    limit_threads(1)
    runs = Path(args.runs)
    res = {name: evaluate(runs / name) for name in RUNS if (runs / name / "summary.json").exists()}
    lines = [
        "# Training behind the filter: results",
        "",
        "Written by `python -m benchmarks.reports.training_results --runs runs` after the runs "
        "below, on "
        "this machine (2 cores, one torch thread a run; two runs at a time). Each run's "
        f"`best_model.zip` (chosen on the validation seeds 900000+) is evaluated on {EPISODES} "
        f"held-out seeds {SEED}..{SEED + EPISODES - 1} with the filter on, against the scripted "
        "controller on the same seeds (same dt, speed limit, filter and time cap): "
        "`python -m rsvo_env.training.evaluate runs/NAME/best_model.zip --episodes 100 --seed 1000 "
        "--compare-scripted`. Completion: the first time every agent is at its goal, over "
        "successful episodes; the paired difference is over the seeds both finish.",
        "",
        "Commands:",
        "",
        "```bash",
        *[RUNS[name] for name in res],
        "```",
        "",
        "## Learned vs scripted",
        "",
        *HEADER,
        *[row(name, r) for name, r in res.items() if not name.startswith("weighting_")],
        "",
        *crowd_section(res, runs),
    ]
    if (RESULTS / GIF).exists():
        lines += [
            f"![the learned residual policy, seed {SEED}]({GIF})",
            "",
            f"`{GIF}`: `circular_residual` on held-out seed {SEED} (written by "
            f"`python -m rsvo_env.training.evaluate runs/circular_residual/best_model.zip "
            "--episodes 1 "
            f"--seed {SEED} --gif benchmarks/results/{GIF}`), played in real time: the six "
            "agents (colour: theta, red egoist to blue altruist) go round one another in a "
            "roundabout instead of meeting in the middle as the scripted controller does.",
            "",
        ]
    lines += weighting_section(res, runs)
    lines += rllib_section(runs)
    for name, title in (
        ("training_speed.md", "Throughput: batched env vs single env (SB3)"),
        ("rllib_speed.md", "RLlib sampling throughput vs the env alone"),
    ):
        path = RESULTS / name
        if path.exists():
            lines += [f"## {title}", path.read_text().split("\n", 1)[1]]
    out = RESULTS / "training.md"
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


def crowd_section(res: dict, runs: Path) -> list[str]:
    """The 12-agent crowd: the config over its training seeds, and without each of its parts,
    each run evaluated with a 40 s and a 100 s time cap."""
    entries = [
        (name, sets, meaning, [f"{name}_s{s}" for s in seeds if f"{name}_s{s}" in res])
        for name, (sets, seeds, meaning) in CROWD.items()
    ]
    plain = ["crowd_plain_gate"] if "crowd_plain_gate" in res else []
    entries.append(("crowd_plain_gate", PLAIN_GATE, "the plain gate, 6 M agent-steps", plain))
    rows, scripted = [], None
    for name, sets, meaning, names in entries:
        if not names:
            continue
        at = {cap: [capped(runs / n, res[n], cap) for n in names] for cap in CROWD_CAPS}
        if scripted is None:
            scripted = {cap: capped(None, res[names[0]], cap) for cap in CROWD_CAPS}
        collisions = sum(res[n]["training_collisions"] for n in names)
        collisions += sum(r["collisions"] for cap in CROWD_CAPS for r in at[cap])
        long = at[CROWD_CAPS[-1]]
        rows.append(
            f"| `{name}` | {meaning} | `{sets or '-'}` | {rates(at[CROWD_CAPS[0]])} | "
            f"{rates(long)} | {np.mean([r['success_rate'] for r in long]):.1%} | "
            f"{np.mean([r['completion_time'] for r in long]):.3f} | {collisions} |"
        )
    if not rows:
        return []
    return [
        "## The crowd (12 agents)",
        "",
        "With the plain gate a parked agent is a fixed obstacle (the filter only slows agents, "
        "it never pushes one aside), and an agent whose goal lies behind parked agents never "
        "reaches it. The crowd config adds three things: `yield_radius: 1.25` (a parked agent's "
        "residual acts again while a neighbour en route is within 1.25 m, so the policy can "
        "step aside), `interaction_radius: 2.0` (the residual of an agent en route acts only "
        "while another agent is within 2 m: alone, an agent follows the scripted command) and "
        "`env.stall_clock: 50` (each agent observes the steps since it last came closer to its "
        "goal). Training episodes end after 40 s; validation and evaluation episodes after "
        "100 s (`validation.max_steps: 1000`), because a jam the policy breaks can take a "
        "minute. Success on the 100 held-out seeds, one entry per training seed, each policy "
        "evaluated with both caps; completion with the 100 s cap, over the successful "
        "episodes; collisions in training and in both evaluations:",
        "",
        "| runs | what | overrides of `training/configs/crowd.yaml` | success, 40 s cap "
        "| success, 100 s cap | mean success, 100 s cap | completion, 100 s cap [s] "
        "| collisions |",
        "|---|---|---|---|---|---|---|---|",
        *rows,
        f"| scripted | the scripted controller | | {scripted[CROWD_CAPS[0]]['success_rate']:.0%} "
        f"| {scripted[CROWD_CAPS[-1]]['success_rate']:.0%} | | "
        f"{scripted[CROWD_CAPS[-1]]['completion_time']:.3f} | "
        f"{sum(scripted[cap]['collisions'] for cap in CROWD_CAPS)} |",
        "",
    ]


def rates(stats: list[dict]) -> str:
    return ", ".join(f"{r['success_rate']:.0%}" for r in stats)


def capped(run: Path | None, r: dict, cap: int) -> dict[str, float]:
    """A crowd run's policy (``run`` None: the scripted controller) on the held-out seeds with
    evaluation episodes of ``cap`` steps (:func:`evaluate` did it already at the run's own)."""
    if evaluation_cap(r["cfg"]) == cap:
        return r["scripted" if run is None else "policy"]
    cfg = {**r["cfg"], "validation": {**r["cfg"]["validation"], "max_steps": cap}}
    if run is None:
        return summarize(run_episodes(cfg, scripted_policy, EPISODES, SEED, "direct"))
    policy, _ = load_model(run / "best_model.zip")
    return summarize(run_episodes(cfg, policy, EPISODES, SEED))


def weighting_section(res: dict, runs: Path) -> list[str]:
    names = [n for n in res if n.startswith("weighting_")]
    if not names:
        return []
    lines = [
        "## Does the R-SVO weighting still shorten completion under a learned policy?",
        "",
        "circular_swap, residual PPO, 3 M agent-steps of training each, 3 training seeds per "
        "weighting; "
        "each policy evaluated under the weighting it was trained with, on the same 100 "
        "held-out seeds (same thetas and rotations).",
        "",
        *HEADER,
        *[row(name, res[name]) for name in names],
        "",
    ]
    means = {}
    for w in ("asymmetric", "symmetric"):
        times = [res[n]["policy"]["completion_time"] for n in names if f"_{w}_" in n]
        scripted = [res[n]["scripted"]["completion_time"] for n in names if f"_{w}_" in n]
        means[w] = (np.mean(times), np.std(times, ddof=1) / np.sqrt(len(times)), scripted[0])
    (ta, sa, ca), (ts, ss, cs) = means["asymmetric"], means["symmetric"]
    lines += [
        "| weighting | learned completion, mean over 3 seeds ± SE [s] | scripted [s] |",
        "|---|---|---|",
        f"| asymmetric (R-SVO) | {ta:.3f} ± {sa:.3f} | {ca:.3f} |",
        f"| symmetric | {ts:.3f} ± {ss:.3f} | {cs:.3f} |",
        f"| asymmetric vs symmetric | {ta / ts - 1:+.1%} | {ca / cs - 1:+.1%} |",
        "",
        f"Answer: with the scripted controller the R-SVO weighting changes completion by "
        f"{ca / cs - 1:+.1%} against the symmetric one; once the nominal policy is learned (each "
        f"policy under the weighting it was trained with) it changes it by {ta / ts - 1:+.1%} "
        f"(3 seeds each).",
        "",
    ]
    # each policy under the other weighting: the weighting's effect with the policy held fixed
    cross = []
    for n in names:
        other = "symmetric" if "_asymmetric_" in n else "asymmetric"
        policy, cfg = load_model(runs / n / "best_model.zip")
        flipped = summarize(run_episodes(cfg, policy, EPISODES, SEED, weighting=other))
        own = res[n]["policy"]
        cross.append(
            f"| {n} | {own['completion_time']:.3f} ({own['success_rate']:.0%}) | "
            f"{flipped['completion_time']:.3f} ({flipped['success_rate']:.0%}) |"
        )
    lines += [
        "The same policies under the other weighting (the weighting's effect with the policy "
        "held fixed):",
        "",
        "| run | own weighting: completion [s] (success) | other weighting |",
        "|---|---|---|",
        *cross,
        "",
    ]
    return lines


def rllib_section(runs: Path) -> list[str]:
    """The RLlib run (evaluated in the distributed venv by the command shown) and its success
    curve beside the SB3 run's; the sweep's table."""
    run, lines = runs / "rllib_circular", []
    if (run / "evaluation.json").exists():
        r = json.loads((run / "evaluation.json").read_text())
        t = json.loads((run / "summary.json").read_text())
        p, s, d = r["policy"], r["scripted"], r["paired_completion_time"]
        lines += [
            "## RLlib PPO (residual, circular_swap)",
            "",
            "```bash",
            RLLIB_RUN,
            "python -m rsvo_env.training.evaluate runs/rllib_circular/best_checkpoint "
            "--episodes 100 --seed 1000 --compare-scripted "
            "--out runs/rllib_circular/evaluation.json",
            "```",
            "",
            f"{t['agent_steps'] / 1e6:.2f} M agent-steps in {t['seconds']:.0f} s of wall time "
            f"({t['agent_steps_per_second']:.0f} agent-steps/s, updates and validations "
            f"included). On 100 held-out seeds: success {p['success_rate']:.0%} (scripted "
            f"{s['success_rate']:.0%}), collisions {p['collisions']}, infeasible steps "
            f"{p['infeasible']}, completion {p['completion_time']:.3f} s vs "
            f"{s['completion_time']:.3f} s scripted, paired {d['mean_difference']:+.3f} ± "
            f"{d['standard_error']:.3f} s ({d['relative_change']:+.1%}).",
            "",
            "Validation (20 held-out seeds) against agent-steps, beside SB3's run "
            "(`circular_residual`):",
            "",
            "| engine | agent-steps | success | completion [s] |",
            "|---|---|---|---|",
            *curve(run / "progress.csv", "rllib", "agent_steps", "eval/"),
            *curve(runs / "circular_residual" / "validation.csv", "sb3", "timesteps", ""),
            "",
        ]
    sweep = runs / "sweep" / "sweep.md"
    if sweep.exists():
        lines += ["## " + sweep.read_text().split("# ", 1)[1], "```bash", SWEEP, "```", ""]
    return lines


def curve(path: Path, engine: str, steps: str, prefix: str) -> list[str]:
    with open(path) as f:
        rows = [r for r in csv.DictReader(f) if r.get(f"{prefix}success_rate")]
    pick = rows[:: max(len(rows) // 6, 1)]
    pick += [r for r in rows[-1:] if r is not pick[-1]]
    return [
        f"| {engine} | {int(float(r[steps])):,} | {float(r[f'{prefix}success_rate']):.0%} | "
        f"{float(r[f'{prefix}completion_time']):.2f} |"
        for r in pick
    ]


RLLIB_RUN = (
    f"{TRAIN} --engine rllib --scenario circular_swap --num-env-runners 1 "
    "--num-envs-per-env-runner 4 --time-limit 600 --timesteps 100000000 "
    "--set validation.every=100000 --out runs/rllib_circular"
)
SWEEP = (
    "python -m rsvo_env.training.sweep --engine rllib --scenario circular_swap "
    "--weightings asymmetric symmetric --thetas random paper --seeds 0 1 --timesteps 100000 "
    "--episodes 100 "
    "--out runs/sweep"
)


if __name__ == "__main__":
    sys.exit(main())
