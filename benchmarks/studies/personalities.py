"""What personalities buy: fixed assignments (searched, the paper's, equal, random) and theta
learned online, written to benchmarks/results/personalities.md with figures of learned thetas.

The searches run in the ``distributed`` venv (Ray Tune, Optuna), the rest in the main one:

    python -m rsvo_env.training.theta_search --trials 300 --out runs/search_c6
    python -m rsvo_env.training.theta_search --set num_agents=12 --trials 300 --out runs/search_c12
    python -m rsvo_env.training.theta_search --scenario doorway --seeds 0 1 2 3 4 --trials 200 \
        --out runs/search_doorway
    python -m benchmarks.studies.personalities --search runs/search_c6 runs/search_c12 \
        runs/search_doorway --runs runs

``--replace`` reruns the scripted sections alone (those of the searches given, and the random
crowds'), each in place of its namesake in the results file, e.g. after a change to R-ORCA:

    python -m benchmarks.studies.personalities --replace --search runs/search_doorway

The learned sections need the training runs whose commands the results file lists (circular
game and crowd, three variants, three training seeds each); a missing run leaves its section
out. Fixed assignments run the scripted controller behind the filter
(``rsvo_env.training.personalities``); learned ones each config's residual policy.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.harness import RESULTS, ROOT
from benchmarks.reports.liveness_report import replace_section
from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.training.config import limit_threads
from rsvo_env.training.evaluate import load_model
from rsvo_env.training.personalities import alternating, evaluate
from rsvo_env.training.seeded_episodes import run_episodes

OUT = RESULTS
EPISODES, SEED = 100, 1000
LEARNED_PREFIX = "## Theta learned online"
RANDOM_SETS = 200
# the crowd as benchmarks/studies/liveness.py runs it: gamma dt = 1, room to finish
CROWD = {"dt": 0.05, "gamma": 20.0, "max_steps": 4000}
LEARNED = {
    "symmetric": "residual, symmetric weights",
    "asymmetric": "residual, R-SVO weights, theta drawn from U(1, 10) each episode",
    "theta_action": "residual and theta chosen every step",
}
FLAGS = {
    "symmetric": "--weighting symmetric",
    "asymmetric": "--weighting asymmetric",
    "theta_action": "--set env.theta_action=true",
}
# the learned studies: each variant's run folder (training seed s) and the budget
STUDIES = {
    "circular_swap": {
        "title": "circular game, 6 agents",
        "config": "residual on the paper's controller, dt 0.1, random rotation, 3 M agent-steps",
        "budget": " --timesteps 3000000",
        "names": {
            "symmetric": "weighting_symmetric_s{s}",
            "asymmetric": "weighting_asymmetric_s{s}",
            "theta_action": "theta_action_s{s}",
        },
    },
    "crowd": {
        "title": "crowd, 12 agents",
        "config": "residual on the paper's controller with yielding, interaction radius and "
        "stall clock, dt 0.1, held-out episodes capped at 100 s; 5 M agent-steps, a third of "
        "the config's budget, the same for every variant",
        "budget": " --timesteps 5000000",
        "names": {v: f"crowd_{v}_s{{s}}" for v in LEARNED},
    },
}


def spread(values: np.ndarray) -> str:
    """Median, 10th-90th percentile and extremes of the finished values."""
    v = values[np.isfinite(values)]
    if not len(v):
        return "none finished"
    q = np.percentile(v, [10, 50, 90])
    return f"median {q[1]:.0f} (10-90 %: {q[0]:.0f}-{q[2]:.0f}; {v.min():.0f}-{v.max():.0f})"


def fixed_section(search: Path, lines: list[str]) -> None:
    """A scenario's scripted controller behind the filter under the searched assignment, the
    paper's, equal scores and random ones on the search's seeds, then on 100 held-out seeds
    (the circular game: each rotating the circle at random)."""
    report = json.loads((search / "search.json").read_text())
    scenario, kwargs, seeds = report["scenario"], report["kwargs"], report["seeds"]
    n, (low, high) = len(report["best"]["theta"]), report["range"]
    rng = np.random.default_rng(0)
    equal, paper, best = "equal (= symmetric weights)", "alternating 2, 1, 2, ...", "searched"
    sets = {
        equal: np.ones((1, n)),
        paper: np.array([alternating(n)]),
        f"random, log-uniform on [{low:g}, {high:g}] ({RANDOM_SETS} sets)": np.exp(
            rng.uniform(np.log(low), np.log(high), (RANDOM_SETS, n))
        ),
        f"random, U(1, 10) ({RANDOM_SETS} sets)": rng.uniform(1.0, 10.0, (RANDOM_SETS, n)),
        best: np.array([report["best"]["theta"]]),
    }
    stats = {name: evaluate(th, seeds, scenario, **kwargs) for name, th in sets.items()}

    def completion(s: dict[str, np.ndarray]) -> np.ndarray:
        """Each assignment's mean completion over the seeds (NaN if one never completes)."""
        return np.where(s["completed"] >= 0, s["completed"], np.nan).mean(axis=1)

    # the reference: equal scores, or the paper's assignment where equal scores never finish
    ref_name = equal if np.isfinite(completion(stats[equal])[0]) else paper
    base = completion(stats[ref_name])[0]
    short = "equal" if ref_name == equal else "alternating"
    controller = "the paper's (`nominal=move_to_goal`)" if "nominal" in kwargs else "R-ORCA"
    others = {k: v for k, v in kwargs.items() if k != "nominal"}
    lines += [
        f"## {scenario}, {n} agents: fixed assignments",
        "",
        f"Scripted controller {controller} behind the filter, the scenario's parameters"
        f"{' with ' + str(others) if others else ''}"
        f", steps of {BatchedEnv(scenario, **kwargs).sim.dt:g} s, seeds {seeds}. The search: "
        f"`{report['sampler']}`, {report['trials']} trials, each theta log-uniform on "
        f"[{low:g}, {high:g}]; the best theta by agent index: "
        f"{np.round(report['best']['theta'], 3).tolist()}.",
        "",
        f"| assignment | completion [steps] | gain over {short} | deadlock resolution [steps] | "
        "sets finishing every seed | collision steps | infeasible agent-steps | "
        "min distance [m] |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, s in stats.items():
        done = completion(s)
        gains = 1.0 - done / base
        if len(done) == 1:
            finished = np.isfinite(done[0])
            comp = f"{done[0]:.0f}" if finished else "never all at goal"
            gain = f"{gains[0]:+.1%}" if finished else "-"
            some = np.isfinite(s["resolution"]).any()
            res = f"{np.nanmean(s['resolution']):.0f}" if some else "-"
        else:
            # an assignment whose episodes never deadlock has no resolution time
            counted = np.isfinite(s["resolution"])
            total = np.where(counted, s["resolution"], 0.0).sum(axis=1)
            per_set = total / np.maximum(counted.sum(axis=1), 1)
            res_mean = np.where(counted.any(axis=1), per_set, np.nan)
            comp, res = spread(done), spread(res_mean)
            g = gains[np.isfinite(gains)]
            gain = f"mean {g.mean():+.1%}, best {g.max():+.1%}" if len(g) else "-"
        lines.append(
            f"| {name} | {comp} | {gain} | {res} | {np.isfinite(done).sum()} / {len(done)} | "
            f"{int(s['collision_steps'].sum())} | {int(s['infeasible'].sum())} | "
            f"{np.nanmin(s['min_distance']):.3f} |"
        )
    held_seeds = list(range(SEED, SEED + EPISODES))
    held_kwargs = {**kwargs, "random_rotation": True} if scenario == "circular_swap" else kwargs
    held = {k: evaluate(sets[k], held_seeds, scenario, **held_kwargs) for k in (equal, paper, best)}
    ref = held[ref_name]["completed"][0]
    how = ", each rotating the circle by a random angle" if scenario == "circular_swap" else ""
    lines += [
        "",
        f"The same on {EPISODES} held-out seeds ({SEED}..{SEED + EPISODES - 1}{how}), paired "
        f"against {short} seed by seed, over the seeds both finish:",
        "",
        "| assignment | finished | completion [steps], mean | deadlock resolution [steps], "
        "mean | paired difference ± SE | collision steps | infeasible agent-steps |",
        "|---|---|---|---|---|---|---|",
    ]
    lines += [held_row(k, h, ref) for k, h in held.items()]
    lines.append("")


def random_section(scenario: str, kwargs: dict[str, Any], lines: list[str]) -> None:
    """A scenario whose layout changes with the seed, where a theta vector by agent index means
    nothing: equal scores against every episode drawing its thetas from U(1, 10), paired on
    the same held-out seeds."""
    seeds = list(range(SEED, SEED + EPISODES))
    equal = evaluate(np.ones((1, kwargs["num_agents"])), seeds, scenario, **kwargs)
    drawn = evaluate(None, seeds, scenario, theta_range=[1.0, 10.0], **kwargs)
    ref = equal["completed"][0]
    lines += [
        f"## {scenario}, {kwargs['num_agents']} agents: equal against random personalities",
        "",
        f"The scenario's scripted controller (R-ORCA) behind the filter, {kwargs}; "
        f"{EPISODES} held-out seeds {SEED}..{SEED + EPISODES - 1}, a new layout each, paired "
        "seed by seed over the seeds both finish.",
        "",
        "| theta | finished | completion [steps], mean | deadlock resolution [steps], mean | "
        "paired difference ± SE | collision steps | infeasible agent-steps |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, h in (("equal", equal), ("U(1, 10) each episode", drawn)):
        lines.append(held_row(name, h, ref))
    lines.append("")


def held_row(name: str, h: dict[str, np.ndarray], ref: np.ndarray) -> str:
    """One row of held-out results paired against ``ref`` (completion steps, -1 unfinished)."""
    c = h["completed"][0]
    ok = (c >= 0) & (ref >= 0)
    d = c[ok] - ref[ok]
    se = d.std(ddof=1) / np.sqrt(len(d)) if len(d) > 1 else np.nan
    paired = f"{d.mean():+.1f} ± {se:.1f} ({d.mean() / ref[ok].mean():+.1%})" if ok.any() else "-"
    mean = f"{c[c >= 0].mean():.1f}" if (c >= 0).any() else "-"
    res = f"{np.nanmean(h['resolution']):.1f}" if np.isfinite(h["resolution"]).any() else "-"
    return (
        f"| {name} | {(c >= 0).sum()} / {len(c)} | {mean} | {res} | {paired} | "
        f"{int(h['collision_steps'].sum())} | {int(h['infeasible'].sum())} |"
    )


def learned_section(runs: Path, scenario: str, lines: list[str]) -> bool:
    """Each variant's 3 training seeds on the held-out seeds, paired against the symmetric
    run of the same training seed; False (and nothing written) when a run is missing."""
    study = STUDIES[scenario]
    records: dict[str, list[dict[str, np.ndarray]]] = {}
    for variant, pattern in study["names"].items():
        for s in (0, 1, 2):
            path = runs / pattern.format(s=s) / "best_model.zip"
            if not path.exists():
                print(f"missing {path}: the learned section of {scenario} is left out")
                return False
            policy, cfg = load_model(path)
            out = run_episodes(cfg, policy, EPISODES, SEED)
            records.setdefault(variant, []).append(out)
    lines += [
        f"{LEARNED_PREFIX} ({study['title']})",
        "",
        f"The config `training/configs/{scenario}.yaml` ({study['config']}), three training "
        f"seeds a variant; each run's `best_model.zip` on {EPISODES} held-out seeds "
        f"{SEED}..{SEED + EPISODES - 1}. Paired: the mean completion over the seeds both finish "
        "against that of the symmetric run of the same training seed; mean ± SE over the three "
        "training seeds.",
        "",
        "| variant | success (per training seed) | completion [s] (per training seed) | "
        "paired vs symmetric | collisions | infeasible steps | min distance [m] |",
        "|---|---|---|---|---|---|---|",
    ]
    for variant, outs in records.items():
        diffs = []
        for out, sym in zip(outs, records["symmetric"], strict=True):
            ok = out["success"].astype(bool) & sym["success"].astype(bool)
            diffs.append(out["completion_time"][ok].mean() / sym["completion_time"][ok].mean() - 1)
        diffs = np.array(diffs)
        succ = ", ".join(f"{o['success'].mean():.0%}" for o in outs)
        comp = ", ".join(f"{np.nanmean(o['completion_time']):.3f}" for o in outs)
        se = diffs.std(ddof=1) / np.sqrt(len(diffs))
        paired = "-" if variant == "symmetric" else f"{diffs.mean():+.1%} ± {se:.1%}"
        lines.append(
            f"| {LEARNED[variant]} | {succ} | {comp} | {paired} | "
            f"{int(sum(o['collision_steps'].sum() for o in outs))} | "
            f"{int(sum(o['infeasible'].sum() for o in outs))} | "
            f"{min(o['min_distance'].min() for o in outs):.3f} |"
        )
    lines += ["", "Commands (S = 0, 1, 2):", ""]
    lines += [
        f"- `python -m rsvo_env.training.train --scenario {scenario} {FLAGS[v]} --seed S"
        f"{study['budget']} --out runs/{name.format(s='S')}`"
        for v, name in study["names"].items()
    ]
    lines.append("")
    return True


def theta_trace(run: Path, seed: int) -> dict[str, Any]:
    """One held-out episode of a learned theta policy: each agent's theta (T, N), its distance
    to its goal (T, N), the step length and the theta range."""
    from rsvo_env.training.config import make_env

    policy, cfg = load_model(run / "best_model.zip")
    env = make_env(cfg, num_envs=1, autoreset_mode="next_step")
    obs, _ = env.reset(seed=seed)
    thetas, dists = [], []
    for _ in range(env.sim.max_steps):
        obs, _, term, trunc, info = env.step(policy(obs, env))
        thetas.append(info["theta"][0].copy())
        s = env.sim.state
        dists.append(np.linalg.norm(s.goals[0] - s.positions[0], axis=-1))
        if term[0] or trunc[0]:
            break
    m = env.sim.theta_action
    return {
        "theta": np.array(thetas),
        "dist": np.array(dists),
        "dt": env.sim.dt,
        "range": (m.theta_min, m.theta_max),
        "tol": env.scenario.params["goal_tolerance"],
    }


def choices(trace: dict[str, Any]) -> str:
    """What the agents chose while en route: the share of agent-steps at the egoistic end of
    the range, and the largest ratio of two agents' thetas at one step."""
    th, en_route = trace["theta"], trace["dist"] > trace["tol"]
    low = trace["range"][0]
    at_low = (th[en_route] <= low * 1.01).mean() if en_route.any() else np.nan
    ratio = np.nanmax(np.where(en_route, th, np.nan).max(1) / np.where(en_route, th, np.nan).min(1))
    return f"{at_low:.0%} of agent-steps en route at the egoistic end, largest ratio {ratio:.2f}"


def theta_figure(trace: dict[str, Any], title: str, path: Path) -> None:
    """Each agent's theta and its distance to its goal against time, one episode."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    th, d = trace["theta"], trace["dist"]
    t = np.arange(1, len(th) + 1) * trace["dt"]
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7.5, 6), sharex=True)
    for i in range(th.shape[1]):
        ax1.plot(t, th[:, i], label=f"agent {i}")
        ax2.plot(t, d[:, i])
    low, high = trace["range"]
    ax1.set_yscale("log")
    ax1.set_ylim(low * 0.8, high * 1.25)
    ax1.set_ylabel("theta chosen (log)\nlow = egoistic")
    ax1.legend(ncol=4, fontsize=7)
    ax1.set_title(title)
    ax2.set_ylabel("distance to goal [m]")
    ax2.set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--search", nargs="+", type=Path, default=[], help="theta_search outputs")
    p.add_argument("--runs", type=Path, default=ROOT / "runs")
    p.add_argument("--out", type=Path, default=OUT)
    p.add_argument(
        "--replace",
        action="store_true",
        help="rerun the scripted sections alone (the --search outputs' and the random crowds'),"
        " each replacing its namesake in --out's personalities.md; the rest stays",
    )
    args = p.parse_args(argv)
    limit_threads(1)
    args.out.mkdir(parents=True, exist_ok=True)
    if args.replace:
        runs = [(fixed_section, (search,)) for search in args.search]
        runs += [(random_section, ("crowd", {"num_agents": n, **CROWD})) for n in (12, 100)]
        for section_of, run_args in runs:
            section: list[str] = []
            section_of(*run_args, section)
            replace_section(args.out / "personalities.md", section[0], section, LEARNED_PREFIX)
        return 0
    lines = [
        "# What personalities buy",
        "",
        "Written by `python -m benchmarks.studies.personalities` (commands in its docstring and "
        "`docs/personalities.md`). Every pair's weights sum to 1 in every row below, so the "
        "guarantee holds throughout; collisions and infeasible steps are counted anyway.",
        "",
    ]
    for search in args.search:
        fixed_section(search, lines)
    for n in (12, 100):
        random_section("crowd", {"num_agents": n, **CROWD}, lines)
    for scenario, study in STUDIES.items():
        if not learned_section(args.runs, scenario, lines):
            continue
        runs = [args.runs / study["names"]["theta_action"].format(s=s) for s in (0, 1, 2)]
        traces = [theta_trace(run, SEED) for run in runs]
        figure = f"personalities_theta_{scenario}.png"
        title = f"Learned theta, {study['title']}, training seed 0, held-out seed {SEED}"
        theta_figure(traces[0], title, args.out / figure)
        lines += [
            f"![learned thetas, {study['title']}]({figure})",
            "",
            f"What the theta policies chose in held-out episode {SEED}, by training seed: "
            + "; ".join(f"seed {s}: {choices(tr)}" for s, tr in enumerate(traces))
            + ".",
            "",
        ]
    (args.out / "personalities.md").write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
