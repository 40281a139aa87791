"""The reproduction's report: markdown sections and tables from the studies' data, the list of
differences from the paper, and README's results block. No computation happens here."""

from __future__ import annotations

import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from rsvo_env.cli.studies import PAPER, Plan, defaults
from rsvo_env.cli.studies.ramp_merge import SPLITS
from rsvo_env.cli.studies.who_benefits import MEASURES

README_START, README_END = "<!-- results:start -->", "<!-- results:end -->"


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


def position_swap(ps: dict) -> list[str]:
    p = defaults("position_swap")
    (x1, y1), (x2, y2) = p["start"]
    lines = [
        "## 1. Position swap (paper Fig. 3)",
        "",
        f"Two agents swap corners, ({x1:g}, {y1:g}) and ({x2:g}, {y2:g}); weights omega_1 / "
        "omega_2 set through theta; distances and mean speeds up to the step the agents meet "
        f"(the right-hand rule first fires, a neighbour within {p['rh_trigger_factor']:g} R).",
        "",
    ]
    rows = [
        [
            fmt(r["R"], 0),
            f"{r['w1']:.1f} / {1 - r['w1']:.1f}",
            *r["distance"],
            *r["speed"],
            r["ratio"],
            r["onset"],
            r["completed"],
            r["min_distance"],
            r["collisions"],
        ]
        for r in ps["rows"]
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
    return lines + [
        f"The agent with the larger omega travels farther before the agents meet in every "
        f"unequal case: ratio {ps['ratio_min']:.3f} to {ps['ratio_max']:.3f}.",
        "",
        "![position swap](position_swap.png)",
        "",
    ]


def ramp_merge(rm: dict, plan: Plan) -> list[str]:
    p = defaults("ramp_merge")
    mx, my = p["merge_point"]
    lines = [
        "## 2. Ramp merge (paper Fig. 4)",
        "",
        f"Double integrator, |a| <= {p['a_max']:g} m/s^2 per component, safety distance "
        f"{p['safety_radius']:g} m, merge point ({mx:g}, {my:g}), both vehicles "
        f"{p['start_distance']:g} m before it at {p['v0']:g} m/s. V1 is on the left lane. "
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
        for (s, b), a in rm["summary"].items()
    ]
    safe = f"{p['safety_radius']:g} m"
    lines += table(
        [
            "split",
            "barrier",
            "runs",
            "egoist merges first",
            f"runs below {safe}",
            "worst min distance [m]",
            "infeasible agent-steps",
        ],
        rows,
    )
    lines += [f"### Default setting ({p['lane_angle_deg']:g}°, gamma {p['gamma']:g})", ""]
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
        rm["detail"],
    )
    return lines + ["![ramp merge](ramp_merge.png)", ""]


def circular(cg: dict, plan: Plan) -> list[str]:
    p = defaults("circular_swap")
    lines = [
        "## 3. Circular game (paper Figs. 5-7)",
        "",
        f"Six agents on a circle of radius {p['circle_radius']:g} swap with the antipodal agent; "
        f"R = {p['safety_radius']:g}, u_max = {p['u_max']:g}, k = {p['k']:g}, gamma = "
        f"{p['gamma']:g}, right-hand rule {p['rh_angle_deg']:g}° within {p['rh_trigger']:g} m. "
        f"Steps of {p['dt']:g} s.",
        "",
        "### The paper's example, theta = (2, 1, 2, 1, 2, 1)",
        "",
    ]
    rows = []
    runs = cg["runs"]
    cases = [("symmetric", runs["sym"], PAPER["sym"]), ("asymmetric", runs["asym"], PAPER["asym"])]
    cases += [(f"{w}, no right-hand rule", o, ("—",) * 3) for w, o in cg["no_rule_runs"].items()]
    for name, out, paper in cases:
        o, r, c = out["deadlock_onset"], out["deadlock_resolved"], out["completed"]
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
        f"Resolution efficiency gain {pct(cg['resolution_gain'])} (paper 46.8 %); completion gain "
        f"{pct(cg['completion_gain'])} (paper 33 %).",
        "",
        "![circular, symmetric](circular_symmetric.png) "
        "![circular, asymmetric](circular_asymmetric.png)",
        "",
        "GIFs: `circular_symmetric.gif`, `circular_asymmetric.gif`.",
        "",
        "### Random theta sets (distinct integers 1..10, seed "
        f"{plan.seed}), against the symmetric run",
        "",
        "The symmetric filter ignores theta, so one symmetric run serves every set.",
        "",
    ]
    rows = []
    for label, (_n, gr, gc, fails) in cg["stats"].items():
        rows.append([f"{label}: resolution gain", *spread(gr), "46.8 %", fails])
        rows.append([f"{label}: completion gain", *spread(gc), "33 %", fails])
    lines += table(
        ["", "sets", "mean", "median", "std", "min", "max", "paper", "sets not completed"], rows
    )
    return lines + [
        f"Collision steps over all random sets: {cg['random_collisions']}; infeasible "
        f"agent-steps: {cg['random_infeasible']}.",
        "",
        "![average minimum distance](avg_min_distance.png)",
        "",
    ]


def who_benefits(wb: dict, n_sets: int) -> list[str]:
    lines = [
        "## 4. Who benefits the most?",
        "",
        f"Per agent over the {n_sets} random theta sets of section 3: the three agents "
        "of a set with the smallest theta are its egoists, the other three its altruists. "
        "Deviation is the integral of |u_safe - u_nominal| over the episode.",
        "",
    ]
    return lines + table(
        [
            "per agent",
            "egoists mean",
            "egoists median",
            "altruists mean",
            "altruists median",
            "rank correlation with theta",
        ],
        [[name, *wb[name]] for name in MEASURES],
    )


def differences(ps: dict, rm: dict, cg: dict) -> list[str]:
    """One sentence for each place where our numbers differ from the paper's, with the reason."""
    o_s, r_s, c_s = cg["sym"]
    o_a, r_a, c_a = cg["asym"]
    cap, pap = rm["capability"], rm["paper"]
    small = cg["stats"]["paper protocol"]
    tail_ours, tail_paper = c_a - r_a, PAPER["asym"][2] - PAPER["asym"][1]
    r1, r2 = ps["ratio_by_radius"][1.0], ps["ratio_by_radius"][2.0]
    c = defaults("circular_swap")
    return [
        f"- Circular game, symmetric: onset / resolved / completed {o_s} / {r_s} / {c_s} "
        "against the paper's 140 / 390 / 620. The paper does not define its right-hand rule; "
        f"ours ({c['rh_angle_deg']:g}° clockwise while a neighbour is within "
        f"{c['rh_trigger']:g} m) is our own choice.",
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
        "the larger share of a negative budget binds the egoist harder "
        "(`docs/double_integrator.md`). The capability split (sign-aware, clipped to what each "
        f"vehicle can do) lets the egoist merge first in {cap['egoist_first']} of "
        f"{cap['unequal']} runs, with {cap['infeasible']} infeasible agent-steps and "
        f"{cap['unsafe']} runs below the safety distance. With equal theta the paper reports a "
        "deadlock; ours end side by side, at the safety distance, through the merge point (our "
        "vehicles are points that may share the main lane's width).",
        f"- Position swap: the larger-omega agent travels {r1:.3f} times as far as the other "
        f"before they meet at R_safe = 1 and {r2:.3f} times at R_safe = 2; the paper says the "
        "allocation is easier to see at the larger margin, ours is smaller there because the "
        "agents meet earlier (the right-hand rule's trigger grows with R) and both stay near "
        "the speed limit for most of the shorter approach.",
    ]


def readme_block(ps: dict, rm: dict, cg: dict, diff: list[str], rel: Path | str) -> list[str]:
    """README's results block: the headline tables, figures and differences."""
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
            ["symmetric (paper)", *PAPER["sym"], "", ""],
            [
                "asymmetric (ours)",
                o_a,
                r_a,
                c_a,
                pct(cg["resolution_gain"]),
                pct(cg["completion_gain"]),
            ],
            ["asymmetric (paper)", *PAPER["asym"], "46.8 %", "33 %"],
        ],
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
            for split, a in ((s, rm["summary"][(s, "braking")]) for s in SPLITS)
        ],
    )
    return [
        f"Produced by `rsvo reproduce` (all tables, and the run's wall time: `{rel}/paper.md`).",
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
    ]


def write_readme(lines: list[str], readme: Path) -> None:
    """Replace README's results block (between the markers) with ``lines``."""
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
