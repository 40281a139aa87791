"""Every model alive: the crowd, the doorway and the obstacle field with single integrators,
double integrators and unicycles (``dynamics=``), each under its scene's scripted controller
behind the filter (R-ORCA; the double integrator tracks its velocity under the acceleration
box, the unicycle steers its look-ahead point, ``docs/liveness.md``).

Per model and scene, over seeds batched in one ``BatchedEnv``: the share of agents that reached
their goals, the episodes in which every agent did, the makespan (the step the last did), the
agent-steps in contact and with an infeasible QP, the closest pair of bodies.

Writes the section "Every model" of ``benchmarks/results/liveness.md``.

    python -m benchmarks.studies.liveness_models [--quick]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from benchmarks.harness import RESULTS
from benchmarks.reports.liveness_report import MODELS_HEADING, replace_section
from rsvo_env.dynamics.unicycle import Unicycle
from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.scenarios import make_scenario

HEADING = MODELS_HEADING
MODELS = ("single_integrator", "double_integrator", "unicycle")
CROWD = {"dt": 0.05, "gamma": 20.0, "theta_range": (1.0, 10.0)}  # the crowd table's setting
L = Unicycle.scenario_defaults["lookahead"]


def run(scene: str, model: str, n: int, seeds: range, cap: int, **kw) -> dict:
    """Episodes of ``scene`` on ``seeds`` at once, ``cap`` steps at most."""
    env = BatchedEnv(scene, num_envs=len(seeds), num_agents=n, dynamics=model, max_steps=cap, **kw)
    env.reset(seed=list(seeds))
    E = len(seeds)
    reached = np.zeros((E, n), dtype=bool)
    makespan = np.full(E, -1)
    contacts = infeasible = 0
    closest = np.inf
    t0 = time.perf_counter()
    for step in range(1, cap + 1):
        _, _, _, _, info = env.step(env.nominal_actions())
        live = makespan < 0  # an env whose agents all arrived restarts: not counted on
        reached[live] |= info["at_goal"][live]
        contacts += int((info["cost"][live] > 0).sum())
        infeasible += int((~info["feasible"][live]).sum())
        closest = min(closest, float(info["min_distance"][live].min()))
        makespan[live & reached.all(1)] = step
        if (makespan > 0).all():
            break
    return {
        "scene": scene,
        "model": model,
        "n": n,
        "seeds": E,
        "cap": cap,
        "arrived": reached.mean(1),
        "makespan": makespan,
        "contacts": contacts,
        "infeasible": infeasible,
        "closest": closest,
        "seconds": time.perf_counter() - t0,
    }


def ratio(row: dict, base: dict) -> str:
    """Mean makespan over the seeds where both finished, this row's over the base's."""
    both = (row["makespan"] > 0) & (base["makespan"] > 0)
    if not both.any():
        return "-"
    r = row["makespan"][both].mean() / base["makespan"][both].mean()
    return f"{r:.2f} ({int(both.sum())} seeds)"


def line(row: dict, base: dict | None) -> str:
    done = row["makespan"] > 0
    span = f"{row['makespan'][done].mean():.0f}" if done.any() else "-"
    return (
        f"| {row['label']} | {row['n']:,} | {row['seeds']} | {row['cap']:,} |"
        f" {100 * row['arrived'].mean():.2f} %, {100 * row['arrived'].min():.1f} % |"
        f" {int(done.sum())} of {row['seeds']} | {span} |"
        f" {ratio(row, base) if base is not None else '-'} | {row['contacts']} |"
        f" {row['infeasible']} | {row['closest']:.4f} |"
    )


HEAD = [
    "| model | N | seeds | cap [steps] | arrived (mean, worst seed) | episodes finished |"
    " makespan [steps] (mean over finished) | makespan / single integrator's (ratio of means,"
    " seeds where both finished) | contact agent-steps | infeasible agent-steps |"
    " closest pair [m] |",
    "|---|---|---|---|---|---|---|---|---|---|---|",
]


def table(rows: list[dict], base: dict | None) -> list[str]:
    return [*HEAD, *(line(r, base) for r in rows), ""]


def crowd_rows(n: int, seeds: range, cap: int, **kw) -> list[dict]:
    rows = []
    for model in MODELS:
        r = run("crowd", model, n, seeds, cap, **kw)
        r["label"] = model.replace("_", " ")
        rows.append(r)
        print("crowd", n, model, r["arrived"].mean(), r["makespan"].tolist(), flush=True)
    # the unicycle's layout is 4 look-aheads wider: the single integrator on those very starts
    # and goals, for its ratio, the scenario's own spacing and side given as its factors
    uni = make_scenario("crowd", dynamics="unicycle", num_agents=n)
    R = uni.params["safety_radius"]
    base = run(
        "crowd",
        "single_integrator",
        n,
        seeds,
        cap,
        spacing_factor=uni.spacing / R,
        side_factor=uni.side / (np.sqrt(n) * R),
        **kw,
    )
    base["label"] = "single integrator, the unicycle's layout"
    rows.append(base)
    return rows


def crowd_section(rows: list[dict], note: str) -> list[str]:
    si, di, uni, si_wide = rows
    return [
        note,
        "",
        *HEAD,
        line(si, si),
        line(di, si),
        line(uni, si_wide),
        line(si_wide, si_wide),
        "",
    ]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="2 seeds, no crowd of 1,000")
    ap.add_argument("--out", type=Path, default=RESULTS / "liveness.md")
    args = ap.parse_args(argv)
    seeds = range(2) if args.quick else range(10)
    out = [
        HEADING,
        "",
        "Written by `python -m benchmarks.studies.liveness_models`: every model in the crowd, the"
        " doorway and the obstacle field (`dynamics=`), each under its scene's scripted"
        " controller behind the filter: R-ORCA's velocity, itself for the single integrator,"
        " tracked under the acceleration box for the double integrator (`a = k_v (v - v_now)`,"
        " k_v = 8, a_max = 2, the speed capped at `sqrt(a_max d)` short of the goal, behind the"
        " stopping-segment barrier, the default), on the look-ahead point"
        " for the unicycle (bodies"
        f" enlarged by the look-ahead l = {L} m, turning in place where the velocity lies"
        " behind). Seeds 0 to 9, theta 1..10. The unicycle's ratio is against the single"
        " integrator on the unicycle's own starts and goals (its layout is 4 look-aheads wider);"
        " its closest pair is of axles (the filter holds the look-ahead points R + 2 l apart).",
        "",
    ]
    rows = crowd_rows(100, seeds, 4000, **CROWD)
    out += crowd_section(rows, "### Crowd of 100, dt = 0.05, gamma = 20 (as the crowd table)")
    rows = crowd_rows(100, seeds, 20000, theta_range=(1.0, 10.0))
    out += crowd_section(
        rows,
        "### Crowd of 100 at the scenario's defaults (dt = 0.01, gamma ="
        " 10), the step limit raised to 20,000",
    )
    if not args.quick:
        big = []
        for model in MODELS[1:]:
            r = run("crowd", model, 1000, range(2), 8000, **CROWD)
            r["label"] = model.replace("_", " ")
            big.append(r)
            print("crowd 1000", model, r["arrived"].mean(), flush=True)
        out += ["### Crowd of 1,000, dt = 0.05, gamma = 20, 8,000 steps", "", *table(big, None)]
    for scene, n in (("doorway", 8), ("doorway", 16), ("obstacle_field", 10)):
        rows = []
        for model in MODELS:
            cap = 4000 if scene == "doorway" else 3000  # the scenes' own step limits
            r = run(scene, model, n, seeds, cap, theta_range=(1.0, 10.0))
            r["label"] = model.replace("_", " ")
            rows.append(r)
            print(scene, n, model, r["arrived"].mean(), r["makespan"].tolist(), flush=True)
        out += [
            f"### {scene.replace('_', ' ').capitalize()}, {n} agents, the scene's defaults"
            " and step limit",
            "",
            *table(rows, rows[0]),
        ]
    replace_section(args.out, HEADING, out, "## Circular swap")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
