"""``rsvo reproduce``: the paper's experiments (Sec. V) as one command, tables and figures.

Writes ``paper.md`` and PNG figures (and two GIFs) to ``--out`` (default
``benchmarks/results``); the full run also refreshes README's Results section. Every number in
``paper.md`` comes from this run; the same seed gives the same file, byte for byte, but for the
line that reports the wall time.
"""

from __future__ import annotations

import argparse
import re
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rsvo_env.cli.simulate import run
from rsvo_env.metrics import completion_gain, resolution_gain
from rsvo_env.responsibility import theta_for_weight

PAPER = {
    "sym": (140, 390, 620),
    "asym": (142, 275, 415),
    "resolution_gain": 0.468,
    "completion_gain": 0.33,
}
ALTERNATING = [2.0, 1.0, 2.0, 1.0, 2.0, 1.0]
README_START, README_END = "<!-- results:start -->", "<!-- results:end -->"
ROOT = Path(__file__).resolve().parents[2]


@dataclass
class Plan:
    """What a run covers: the full study or the quick one."""

    quick: bool
    seed: int

    @property
    def n_random_sets(self) -> tuple[int, int]:
        return (5, 5) if self.quick else (5, 50)

    @property
    def ramp_angles(self) -> tuple[float, ...]:
        return (20.0,) if self.quick else (15.0, 20.0, 30.0)

    @property
    def ramp_gammas(self) -> tuple[float, ...]:
        return (1.0,) if self.quick else (0.5, 1.0, 2.0)


def fmt(x: Any, digits: int = 3) -> str:
    if x is None:
        return "—"
    if isinstance(x, (bool, np.bool_)):
        return "yes" if x else "no"
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    return f"{float(x):.{digits}f}"


def table(header: list[str], rows: Iterable[list[Any]]) -> list[str]:
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += [
        "| " + " | ".join(fmt(c) if not isinstance(c, str) else c for c in r) + " |" for r in rows
    ]
    return out + [""]


def pct(x: float | None) -> str:
    return "—" if x is None else f"{100 * x:.1f} %"


def first_step(trajectory: np.ndarray, agent: int, y: float) -> int | None:
    hit = np.nonzero(trajectory[:, agent, 1] >= y)[0]
    return int(hit[0]) if len(hit) else None


# ---- 1. position swap --------------------------------------------------------------------------
def position_swap(plan: Plan, progress: Callable, figures: dict) -> tuple[list[str], dict]:
    rows, runs, ratios, by_radius = [], {}, [], {}
    for R in (1.0, 2.0):
        for w1 in (0.8, 0.5, 0.2):
            out = run(
                "position_swap", theta=list(theta_for_weight(w1)), safety_radius=R, seed=plan.seed
            )
            progress()
            onset = out["deadlock_onset"]
            seg = out["trajectory"][: (onset or out["steps"]) + 1]
            d = np.linalg.norm(np.diff(seg, axis=0), axis=2).sum(axis=0)
            t = (onset or out["steps"]) * 0.01
            ego = 0 if w1 >= 0.5 else 1
            ratio = d[ego] / d[1 - ego]
            if w1 != 0.5:
                ratios.append(ratio)
                by_radius[R] = ratio
            runs[(R, w1)] = out
            rows.append(
                [
                    fmt(R, 0),
                    f"{w1:.1f} / {1 - w1:.1f}",
                    d[0],
                    d[1],
                    d[0] / t,
                    d[1] / t,
                    ratio,
                    onset,
                    out["completed"],
                    out["min_distance"],
                    out["n_collision_steps"],
                ]
            )
    lines = [
        "## 1. Position swap (paper Fig. 3)",
        "",
        "Two agents swap corners, (-4, -4) and (4, 4); weights omega_1 / omega_2 set through "
        "theta; distances and mean speeds up to the step the agents meet (the right-hand "
        "rule first fires, a neighbour within 1.5 R).",
        "",
    ]
    lines += table(
        [
            "R_safe",
            "omega_1 / omega_2",
            "dist. agent 1 [m]",
            "dist. agent 2 [m]",
            "speed 1 [m/s]",
            "speed 2 [m/s]",
            "larger-omega / other",
            "meet step",
            "completed step",
            "min distance [m]",
            "collision steps",
        ],
        rows,
    )
    lines += [
        f"The agent with the larger omega travels farther before the agents meet in every "
        f"unequal case: ratio {min(ratios):.3f} to {max(ratios):.3f}.",
        "",
        "![position swap](position_swap.png)",
        "",
    ]
    figures["position_swap"] = runs
    return lines, {"ratio_min": min(ratios), "ratio_max": max(ratios), "ratio_by_radius": by_radius}


def position_swap_figure(runs: dict, path: Path) -> None:
    import matplotlib.pyplot as plt

    from rsvo_env.rendering import plot_trajectories

    fig, axes = plt.subplots(2, 3, figsize=(12, 8))
    for (R, w1), out in runs.items():
        ax = axes[int(R) - 1, [0.8, 0.5, 0.2].index(w1)]
        marks = [out["deadlock_onset"]] if out["deadlock_onset"] else []
        plot_trajectories(
            out["trajectory"],
            out["goals"],
            out["theta"],
            R,
            ax=ax,
            marks=marks,
            title=f"R_safe = {R:g}, omega = {w1:.1f} / {1 - w1:.1f}",
        )
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


# ---- 2. ramp merge -----------------------------------------------------------------------------
RAMP_CASES = {
    "equal theta": [1.0, 1.0],
    "V2 more altruistic": [1.0, 4.0],
    "V2 more egoistic": [4.0, 1.0],
}


def ramp_merge(plan: Plan, progress: Callable, figures: dict) -> tuple[list[str], dict]:
    detail, summary, figure_runs = [], {}, {}
    for split in ("capability", "sign_aware", "paper"):
        for barrier in ("braking", "hocbf"):
            agg = summary.setdefault(
                (split, barrier),
                {
                    "runs": 0,
                    "unequal": 0,
                    "egoist_first": 0,
                    "unsafe": 0,
                    "worst": np.inf,
                    "infeasible": 0,
                },
            )
            for angle in plan.ramp_angles:
                for gamma in plan.ramp_gammas:
                    for case, theta in RAMP_CASES.items():
                        out = run(
                            "ramp_merge",
                            theta=theta,
                            split=split,
                            barrier=barrier,
                            lane_angle_deg=angle,
                            gamma=gamma,
                            seed=plan.seed,
                        )
                        progress()
                        merge_y = 70.0
                        t = [first_step(out["trajectory"], i, merge_y) for i in range(2)]
                        first = (
                            "tie"
                            if t[0] == t[1]
                            else "V1"
                            if (t[1] is None or (t[0] is not None and t[0] < t[1]))
                            else "V2"
                        )
                        agg["runs"] += 1
                        agg["unsafe"] += int(out["min_distance"] < 5.0)
                        agg["worst"] = min(agg["worst"], out["min_distance"])
                        agg["infeasible"] += out["n_infeasible"]
                        if theta[0] != theta[1]:
                            egoist = "V1" if theta[0] < theta[1] else "V2"
                            agg["unequal"] += 1
                            agg["egoist_first"] += int(first == egoist)
                        if angle == 20.0 and gamma == 1.0:
                            detail.append(
                                [
                                    split,
                                    barrier,
                                    case,
                                    first,
                                    t[0],
                                    t[1],
                                    out["min_distance"],
                                    out["n_infeasible"],
                                ]
                            )
                            if barrier == "braking" and split in ("capability", "paper"):
                                figure_runs[(split, case)] = out
    lines = [
        "## 2. Ramp merge (paper Fig. 4)",
        "",
        "Double integrator, |a| <= 5 m/s^2 per component, safety distance 5 m, merge point "
        "(0, 70), both vehicles 60 m before it at 15 m/s. V1 is on the left lane. "
        f"Grid: merge angles {', '.join(f'{a:g}°' for a in plan.ramp_angles)} x gains "
        f"{', '.join(f'{g:g}' for g in plan.ramp_gammas)} x the three theta cases.",
        "",
        "### Summary per design",
        "",
    ]
    rows = [
        [
            s,
            b,
            a["runs"],
            f"{a['egoist_first']} / {a['unequal']}",
            a["unsafe"],
            a["worst"],
            a["infeasible"],
        ]
        for (s, b), a in summary.items()
    ]
    lines += table(
        [
            "split",
            "barrier",
            "runs",
            "egoist merges first",
            "runs below 5 m",
            "worst min distance [m]",
            "infeasible agent-steps",
        ],
        rows,
    )
    lines += ["### Default setting (20°, gamma 1)", ""]
    lines += table(
        [
            "split",
            "barrier",
            "case",
            "first through merge",
            "V1 step",
            "V2 step",
            "min distance [m]",
            "infeasible agent-steps",
        ],
        detail,
    )
    lines += ["![ramp merge](ramp_merge.png)", ""]
    figures["ramp_merge"] = figure_runs
    cap = summary[("capability", "braking")]
    pap = summary[("paper", "braking")]
    return lines, {"capability": cap, "paper": pap, "summary": summary}


def ramp_merge_figure(runs: dict, path: Path) -> None:
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(12, 7), sharey=True)
    for (split, case), out in runs.items():
        ax = axes[0 if split == "capability" else 1, list(RAMP_CASES).index(case)]
        traj = out["trajectory"]
        for i, style in ((0, "-"), (1, "--")):
            ax.plot(
                np.arange(len(traj)) * 0.01,
                traj[:, i, 1],
                style,
                label=f"V{i + 1} (theta {out['theta'][i]:g})",
            )
        ax.axhline(70.0, color="grey", lw=0.8)
        ax.set_title(f"{split} split, {case}", fontsize=9)
        ax.set_xlabel("t [s]")
        ax.legend(fontsize=7)
    axes[0, 0].set_ylabel("y [m] (merge at 70)")
    axes[1, 0].set_ylabel("y [m] (merge at 70)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


# ---- 3. circular game --------------------------------------------------------------------------
def steps_of(out: dict) -> tuple[int | None, int | None, int | None]:
    return out["deadlock_onset"], out["deadlock_resolved"], out["completed"]


def gains(sym: dict, asym: dict) -> tuple[float | None, float | None]:
    o_s, r_s, c_s = steps_of(sym)
    o_a, r_a, c_a = steps_of(asym)
    res = resolution_gain(o_s, r_s, o_a, r_a) if None not in (o_s, r_s, o_a, r_a) else None
    comp = completion_gain(c_s, c_a) if None not in (c_s, c_a) else None
    return res, comp


def random_theta_sets(seed: int, count: int) -> list[list[float]]:
    """Distinct integers 1..10 per set (the paper's protocol), from one seeded generator."""
    rng = np.random.default_rng(seed)
    return [
        rng.choice(np.arange(1, 11), 6, replace=False).astype(float).tolist() for _ in range(count)
    ]


def spread(values: list[float]) -> list[Any]:
    v = np.array(values, dtype=float)
    return [
        len(v),
        pct(v.mean()),
        pct(float(np.median(v))),
        pct(v.std()),
        pct(v.min()),
        pct(v.max()),
    ]


def circular_game(
    plan: Plan, progress: Callable, figures: dict, out_dir: Path
) -> tuple[list[str], dict]:
    sym, asym = (
        run(
            "circular_swap",
            weighting=w,
            theta=ALTERNATING,
            seed=plan.seed,
            gif=out_dir / f"circular_{w}.gif",
        )
        for w in ("symmetric", "asymmetric")
    )
    progress(2)
    no_rule = {
        w: run(
            "circular_swap",
            weighting=w,
            theta=ALTERNATING,
            seed=plan.seed,
            deadlock_resolution="none",
        )
        for w in ("symmetric", "asymmetric")
    }
    progress()
    g_res, g_comp = gains(sym, asym)
    lines = [
        "## 3. Circular game (paper Figs. 5-7)",
        "",
        "Six agents on a circle of radius 5 swap with the antipodal agent; R = 1, u_max = 3, "
        "k = 5, gamma = 12, right-hand rule 60° within 1.1 m. Steps of 0.01 s.",
        "",
        "### The paper's example, theta = (2, 1, 2, 1, 2, 1)",
        "",
    ]
    rows = []
    for name, out, paper in (("symmetric", sym, PAPER["sym"]), ("asymmetric", asym, PAPER["asym"])):
        o, r, c = steps_of(out)
        rows.append(
            [
                name,
                o,
                paper[0],
                r,
                paper[1],
                c,
                paper[2],
                out["min_distance"],
                out["n_collision_steps"],
                out["n_infeasible"],
            ]
        )
    for w, out in no_rule.items():
        o, r, c = steps_of(out)
        rows.append(
            [
                f"{w}, no right-hand rule",
                o,
                "—",
                r,
                "—",
                c,
                "—",
                out["min_distance"],
                out["n_collision_steps"],
                out["n_infeasible"],
            ]
        )
    lines += table(
        [
            "run",
            "deadlock onset",
            "paper",
            "resolved",
            "paper",
            "completed",
            "paper",
            "min distance [m]",
            "collision steps",
            "infeasible agent-steps",
        ],
        rows,
    )
    lines += [
        f"Resolution efficiency gain {pct(g_res)} (paper 46.8 %); completion gain "
        f"{pct(g_comp)} (paper 33 %).",
        "",
        "![circular, symmetric](circular_symmetric.png) "
        "![circular, asymmetric](circular_asymmetric.png)",
        "",
        "GIFs: `circular_symmetric.gif`, `circular_asymmetric.gif`.",
        "",
    ]
    n_small, n_large = plan.n_random_sets
    sets = random_theta_sets(plan.seed, max(n_small, n_large))
    per_set = []
    for theta in sets:
        out = run("circular_swap", theta=theta, seed=plan.seed)
        progress()
        per_set.append(out)
    stats = {}
    for label, n in (("paper protocol", n_small), ("larger study", n_large)):
        if label == "larger study" and n == n_small:
            continue
        gr, gc, fails = [], [], 0
        for out in per_set[:n]:
            r, c = gains(sym, out)
            if r is None or c is None:
                fails += 1
                continue
            gr.append(r)
            gc.append(c)
        stats[label] = (n, gr, gc, fails)
    lines += [
        "### Random theta sets (distinct integers 1..10, seed "
        f"{plan.seed}), against the symmetric run",
        "",
        "The symmetric filter ignores theta, so one symmetric run serves every set.",
        "",
    ]
    rows = []
    for label, (_n, gr, gc, fails) in stats.items():
        rows.append([f"{label}: resolution gain", *spread(gr), "46.8 %", fails])
        rows.append([f"{label}: completion gain", *spread(gc), "33 %", fails])
    lines += table(
        ["", "sets", "mean", "median", "std", "min", "max", "paper", "sets not completed"], rows
    )
    collisions = sum(o["n_collision_steps"] for o in per_set)
    lines += [
        f"Collision steps over all random sets: {collisions}; infeasible agent-steps: "
        f"{sum(o['n_infeasible'] for o in per_set)}.",
        "",
        "![average minimum distance](avg_min_distance.png)",
        "",
    ]
    figures["circular"] = {"sym": sym, "asym": asym, "random": per_set[:n_small]}
    summary = {
        "sym": steps_of(sym),
        "asym": steps_of(asym),
        "resolution_gain": g_res,
        "completion_gain": g_comp,
        "no_rule": {w: steps_of(o) for w, o in no_rule.items()},
        "stats": stats,
        "collisions": collisions + sym["n_collision_steps"] + asym["n_collision_steps"],
        "per_set": per_set,
        "sets": sets,
    }
    return lines, summary


def circular_figures(data: dict, out_dir: Path) -> None:
    import matplotlib.pyplot as plt

    from rsvo_env.rendering import plot_trajectories

    for name in ("sym", "asym"):
        out = data[name]
        marks = [m for m in (out["deadlock_onset"], out["deadlock_resolved"]) if m]
        title = {"sym": "symmetric", "asym": "asymmetric"}[name]
        fig = plot_trajectories(
            out["trajectory"],
            out["goals"],
            out["theta"],
            out["safety_radius"],
            marks=marks,
            title=f"{title}, theta = (2,1,2,1,2,1)",
        )
        fig.savefig(out_dir / f"circular_{title}.png", dpi=100, bbox_inches="tight")
        plt.close(fig)
    fig, ax = plt.subplots(figsize=(7, 4))
    t = np.arange(1, len(data["sym"]["avg_min_distance_series"]) + 1)
    ax.plot(t, data["sym"]["avg_min_distance_series"], label="symmetric")
    series = [o["avg_min_distance_series"] for o in data["random"]]
    longest = max(len(s) for s in series)
    padded = np.array([np.pad(s, (0, longest - len(s)), mode="edge") for s in series])
    ax.plot(
        np.arange(1, longest + 1),
        padded.mean(axis=0),
        label=f"asymmetric, mean of {len(series)} random theta sets",
    )
    ax.plot(
        np.arange(1, len(data["asym"]["avg_min_distance_series"]) + 1),
        data["asym"]["avg_min_distance_series"],
        "--",
        label="asymmetric, (2,1,2,1,2,1)",
    )
    ax.axhline(1.0, color="grey", lw=0.8, label="R_safe")
    ax.set_xlabel("step")
    ax.set_ylabel("average minimum distance D [m]")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out_dir / "avg_min_distance.png", dpi=100)
    plt.close(fig)


# ---- 4. who benefits ---------------------------------------------------------------------------
def who_benefits(circular: dict) -> tuple[list[str], dict]:
    rows_theta, rows_dev, rows_path, rows_arr = [], [], [], []
    for theta, out in zip(circular["sets"], circular["per_set"], strict=True):
        rows_theta.append(theta)
        rows_dev.append(out["deviation"])
        rows_path.append(out["path_length"])
        rows_arr.append(np.where(out["arrival"] >= 0, out["arrival"], out["steps"]))
    theta = np.array(rows_theta)
    egoist = theta < np.median(theta, axis=1, keepdims=True)
    lines = [
        "## 4. Who benefits the most?",
        "",
        f"Per agent over the {len(theta)} random theta sets of section 3: the three agents "
        "of a set with the smallest theta are its egoists, the other three its altruists. "
        "Deviation is the integral of |u_safe - u_nominal| over the episode.",
        "",
    ]
    rows, result = [], {}
    for name, values in (
        ("deviation from nominal [m]", np.array(rows_dev)),
        ("path length [m]", np.array(rows_path)),
        ("arrival step", np.array(rows_arr, dtype=float)),
    ):
        e, a = values[egoist], values[~egoist]
        rho = float(
            np.corrcoef(
                np.argsort(np.argsort(theta.ravel())), np.argsort(np.argsort(values.ravel()))
            )[0, 1]
        )
        rows.append([name, e.mean(), float(np.median(e)), a.mean(), float(np.median(a)), rho])
        result[name] = (float(e.mean()), float(a.mean()), rho)
    lines += table(
        [
            "per agent",
            "egoists mean",
            "egoists median",
            "altruists mean",
            "altruists median",
            "rank correlation with theta",
        ],
        rows,
    )
    return lines, result


# ---- report ------------------------------------------------------------------------------------
def differences(ps: dict, rm: dict, cg: dict) -> list[str]:
    """One sentence for each place where our numbers differ from the paper's, with the reason."""
    o_s, r_s, c_s = cg["sym"]
    o_a, r_a, c_a = cg["asym"]
    cap, pap = rm["capability"], rm["paper"]
    small = cg["stats"]["paper protocol"]
    tail_ours, tail_paper = c_a - r_a, PAPER["asym"][2] - PAPER["asym"][1]
    r1, r2 = ps["ratio_by_radius"][1.0], ps["ratio_by_radius"][2.0]
    return [
        f"- Circular game, symmetric: onset / resolved / completed {o_s} / {r_s} / {c_s} "
        "against the paper's 140 / 390 / 620. The paper does not define its right-hand rule; "
        "ours (60° clockwise while a neighbour is within 1.1 m) is our own choice.",
        f"- Circular game, asymmetric: {o_a} / {r_a} / {c_a} against 142 / 275 / 415. The "
        f"resolution gain ({pct(cg['resolution_gain'])}) matches the paper's 46.8 %, the "
        f"completion gain ({pct(cg['completion_gain'])}) falls short of its 33 % because our "
        f"agents need {tail_ours} steps from resolution to completion against the paper's "
        f"{tail_paper}; the paper gives no detail of that phase (its nominal gain saturates the "
        "speed until the last half metre, so the tail depends on how its agents leave the "
        "centre).",
        "- Random theta sets: the paper's 5-set gains (46.8 % and 33 %) are exactly its single "
        "alternating example's, so we report that example and the random sets apart. Over our "
        f"5 seeded sets the mean gains are {pct(float(np.mean(small[1])))} and "
        f"{pct(float(np.mean(small[2])))}, with a wide spread from set to set (table above).",
        f"- Ramp merge: with the paper's literal split (s = omega RHS) the egoist merges first "
        f"in {pap['egoist_first']} of {pap['unequal']} unequal-theta runs, with "
        f"{pap['infeasible']} infeasible agent-steps: while the vehicles close in, RHS < 0, and "
        "the larger share of a negative budget binds the egoist harder (DESIGN.md section 3). "
        "The capability split (sign-aware, clipped to what each vehicle can do) lets the egoist "
        f"merge first in {cap['egoist_first']} of {cap['unequal']} runs, with "
        f"{cap['infeasible']} infeasible agent-steps and {cap['unsafe']} runs below 5 m. With "
        "equal theta the paper reports a deadlock; ours end side by side, 5 m apart, through "
        "the merge point (our vehicles are points that may share the main lane's width).",
        f"- Position swap: the larger-omega agent travels {r1:.3f} times as far as the other "
        f"before they meet at R_safe = 1 and {r2:.3f} times at R_safe = 2; the paper says the "
        "allocation is easier to see at the larger margin, ours is smaller there because the "
        "agents meet earlier (the right-hand rule's trigger grows with R) and both stay near "
        "the speed limit for most of the shorter approach.",
    ]


def write_readme(lines: list[str], readme: Path) -> None:
    text = readme.read_text()
    block = "\n".join([README_START, *lines, README_END])
    if README_START in text:
        text = re.sub(
            re.escape(README_START) + ".*?" + re.escape(README_END),
            lambda _: block,
            text,
            flags=re.S,
        )
    else:
        text = text.rstrip() + "\n\n## Results\n\n" + block + "\n"
    readme.write_text(text)


def reproduce(
    out_dir: Path, quick: bool = False, seed: int = 0, readme: Path | None = None
) -> dict[str, Any]:
    """Run every study, write ``paper.md`` and the figures; returns the headline numbers."""
    from tqdm import tqdm

    out_dir.mkdir(parents=True, exist_ok=True)
    plan = Plan(quick=quick, seed=seed)
    n_small, n_large = plan.n_random_sets
    total = (
        6 + 3 * 2 * len(plan.ramp_angles) * len(plan.ramp_gammas) * 3 + 3 + max(n_small, n_large)
    )
    t0 = time.perf_counter()
    figures: dict = {}
    with tqdm(total=total, desc="rsvo reproduce", unit="run") as bar:
        ps_lines, ps = position_swap(plan, bar.update, figures)
        rm_lines, rm = ramp_merge(plan, bar.update, figures)
        cg_lines, cg = circular_game(plan, bar.update, figures, out_dir)
    wb_lines, wb = who_benefits(cg)
    position_swap_figure(figures["position_swap"], out_dir / "position_swap.png")
    ramp_merge_figure(figures["ramp_merge"], out_dir / "ramp_merge.png")
    circular_figures(figures["circular"], out_dir)
    wall = time.perf_counter() - t0
    diff = differences(ps, rm, cg)
    header = [
        "# Reproducing the paper",
        "",
        f"Written by `rsvo reproduce{' --quick' if quick else ''}` (seed {seed}). Every "
        "number below comes from this run; the scripted nominal controller runs behind "
        "the R-CBF filter (exact solver).",
        "",
        f"Wall time: {wall:.1f} s",
        "",
    ]
    doc = (
        header
        + ps_lines
        + rm_lines
        + cg_lines
        + wb_lines
        + ["## Where we differ from the paper", "", *diff, ""]
    )
    (out_dir / "paper.md").write_text("\n".join(doc))
    if readme is not None:
        o_s, r_s, c_s = cg["sym"]
        o_a, r_a, c_a = cg["asym"]
        main = table(
            [
                "circular game",
                "deadlock onset",
                "resolved",
                "completed",
                "resolution gain",
                "completion gain",
            ],
            [
                ["symmetric (ours)", o_s, r_s, c_s, "", ""],
                ["symmetric (paper)", 140, 390, 620, "", ""],
                [
                    "asymmetric (ours)",
                    o_a,
                    r_a,
                    c_a,
                    pct(cg["resolution_gain"]),
                    pct(cg["completion_gain"]),
                ],
                ["asymmetric (paper)", 142, 275, 415, "46.8 %", "33 %"],
            ],
        )
        rel = (
            out_dir.resolve().relative_to(readme.resolve().parent)
            if out_dir.resolve().is_relative_to(readme.resolve().parent)
            else out_dir
        )
        sets = table(
            ["random theta sets", "sets", "mean", "median", "std", "min", "max", "paper"],
            [
                row
                for n, gr, gc, _ in cg["stats"].values()
                for row in (
                    [f"resolution gain, {n} sets", *spread(gr), "46.8 %"],
                    [f"completion gain, {n} sets", *spread(gc), "33 %"],
                )
            ],
        )
        ramp = table(
            [
                "ramp merge, braking barrier",
                "egoist merges first",
                "runs below 5 m",
                "infeasible agent-steps",
            ],
            [
                [
                    f"{split} split",
                    f"{a['egoist_first']} / {a['unequal']}",
                    a["unsafe"],
                    a["infeasible"],
                ]
                for (split, barrier), a in rm["summary"].items()
                if barrier == "braking"
            ],
        )
        write_readme(
            [
                f"Produced by `rsvo reproduce` (all tables, and the run's wall time: "
                f"`{rel}/paper.md`).",
                "",
                *main,
                *sets,
                *ramp,
                f"Position swap: the agent with the larger omega travels {ps['ratio_min']:.3f} "
                f"to {ps['ratio_max']:.3f} times as far as the other before they meet.",
                "",
                f"![circular, asymmetric]({rel}/circular_asymmetric.png) "
                f"![average minimum distance]({rel}/avg_min_distance.png)",
                "",
                f"![position swap]({rel}/position_swap.png)",
                "",
                f"![ramp merge]({rel}/ramp_merge.png)",
                "",
                f"GIFs: `{rel}/circular_symmetric.gif`, `{rel}/circular_asymmetric.gif`.",
                "",
                "Where we differ from the paper:",
                "",
                *diff,
            ],
            readme,
        )
    return {
        "position_swap": ps,
        "ramp_merge": rm,
        "circular": cg,
        "who_benefits": wb,
        "wall_time": wall,
        "paper_md": out_dir / "paper.md",
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="rsvo reproduce", description=__doc__)
    ap.add_argument("--quick", action="store_true", help="a small run (about half a minute)")
    ap.add_argument(
        "--out",
        type=Path,
        default=None,
        help="output folder (default benchmarks/results in a checkout, else ./rsvo-results)",
    )
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument(
        "--no-readme", action="store_true", help="do not refresh README's Results section"
    )
    args = ap.parse_args(argv)
    in_checkout = (ROOT / "README.md").exists() and (ROOT / "benchmarks").is_dir()
    out = args.out or (ROOT / "benchmarks" / "results" if in_checkout else Path("rsvo-results"))
    readme = None
    if not (args.quick or args.no_readme or args.out is not None) and in_checkout:
        readme = ROOT / "README.md"
    res = reproduce(out, quick=args.quick, seed=args.seed, readme=readme)
    print(f"wrote {res['paper_md']} in {res['wall_time']:.1f} s")
    return 0 if res["circular"]["collisions"] == 0 else 1
