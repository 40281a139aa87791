"""The tables and the log-log plot of ``benchmarks/speed/scaling.py``."""

from __future__ import annotations

from pathlib import Path

from benchmarks.harness import machine
from rsvo_env.dynamics.unicycle import Unicycle

UNI = Unicycle.scenario_defaults


def plot(rows: list[dict], di: list[dict], path: Path) -> None:
    """µs per agent-step against N, log-log: ours (theta equal, 1..10), ORCA, DI."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 5.4), dpi=120)
    for key, label, style in (
        ("ours_equal", "R-CBF filter, theta equal", "o-"),
        ("ours_spread", "R-CBF filter, theta 1..10", "s-"),
        ("orca", "ORCA (pyrvo, C++ step)", "^--"),
    ):
        pts = [(r["n"], r[key]) for r in rows if r.get(key)]
        if pts:
            ax.plot(*zip(*pts, strict=True), style, label=label)
    for barrier, style in (
        ("segment", "P-"),
        ("backup", "D:"),
        ("braking", "x:"),
        ("unicycle, gamma 10 (the single integrator's)", "v-"),
        ("unicycle, gamma 2 (the double integrator's)", "^:"),
    ):
        pts = [(d["n"], d["di"]) for d in di if d.get("barrier", "braking") == barrier]
        if pts:
            label = (
                f"double integrator, {barrier} barrier"
                if barrier[0] != "u"
                else barrier.split(" (")[0]
            )
            ax.plot(*zip(*pts, strict=True), style, label=f"{label}, theta 1..10")
    # the double integrator's own reference: its ratios are to this run, not to section 1's
    ref = {d["n"]: d["si"] for d in di if d.get("barrier") == "segment"}
    if ref:
        ax.plot(
            list(ref),
            list(ref.values()),
            ".:",
            color="grey",
            label="single integrator, in the double integrator's run",
        )
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("agents N")
    ax.set_ylabel("µs per agent-step (lower is better)")
    ax.set_title("Cost per agent of one filtered step, crowd scenario")
    ax.grid(True, which="both", alpha=0.3)
    # below the axes: inside, it hid the double integrator's points
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2)
    fig.tight_layout()
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)


def di_section(di: list, DT: float, DoubleIntegrator) -> list[str]:
    """Section 2's lines: each barrier's cost against the single integrator's."""
    lines = [
        "## 2. Double-integrator crowds (theta 1..10)",
        "",
        f"Acceleration box |a_k| <= {DoubleIntegrator.A_MAX}, gamma = {DoubleIntegrator.GAMMA},"
        f" dt = {DT}, no user `neighbor_radius` (each agent's radius comes from the speeds and"
        " the box); the stopping-segment barrier (the default, `docs/double_integrator.md`),"
        " the backup barrier (the stopping disk) and the braking barrier with the capability"
        " split. Nominal: a = 2 (v_des - v) with v_des the"
        f" move-to-goal command. The unicycles (look-ahead l = {UNI['lookahead']} m, w_max ="
        f" {UNI['w_max']} rad/s, the scenarios' defaults, their"
        " crowd spread so the look-ahead points start apart) run the single integrator's rows"
        " on their look-ahead points, at the single integrator's gamma and at the double"
        " integrator's; nominal: full speed toward the goal, turning at twice the heading"
        " error. Against the single integrator on the same crowd and theta in"
        " the same run, blocks alternating. Every 20th step the actions and flags are"
        " recomputed with all pairs. Rerun this section alone:"
        " `python -m benchmarks.speed.scaling --di-only`.",
        "",
        "| N | barrier (or model) | double integrator (or unicycle) [µs] |"
        " single integrator [µs] | ratio |"
        " infeasible agent-steps | all-pairs checks (mismatches) | min distance [m] |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for d in di:
        share = d["infeasible"] / max(d["agent_steps"], 1)
        lines.append(
            f"| {d['n']:,} | {d['barrier']} | {d['di']:.2f} | {d['si']:.2f} | "
            f"{d['di'] / d['si']:.1f}x | "
            f"{d['infeasible']:,} of {d['agent_steps']:,} ({100 * share:.2f} %) | "
            f"{d['checks']} ({d['mismatches']}) | {d['min_distance']:.4f} |"
        )
    return lines


def section_one(text: str) -> list[dict]:
    """Section 1's figures read back from a results file (for the plot of a section-2 rerun)."""
    rows = []
    body = text[text.index("## 1. ") : text.index("## 2. ")]
    for line in body.splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) == 9 and cells[0].replace(",", "").isdigit():
            num = [float(c) if c.replace(".", "").isdigit() else None for c in cells]
            rows.append(
                {
                    "n": int(cells[0].replace(",", "")),
                    "ours_equal": num[2],
                    "orca": num[3],
                    "ours_spread": num[5],
                }
            )
    return rows


def splice_di(path: Path, di: list, DT: float, DoubleIntegrator) -> None:
    """Replace section 2 of an existing results file with a new run of it, and redraw the
    figure with section 1 as it stands."""
    text = path.read_text()
    plot(section_one(text), di, path.with_suffix(".png"))
    start = text.index("## 2. ")
    end = text.find("\n## 3. ", start)
    tail = "" if end < 0 else text[end:]
    path.write_text(text[:start] + "\n".join(di_section(di, DT, DoubleIntegrator)) + "\n" + tail)


def write(
    path: Path,
    rows: list,
    di: list,
    big: list,
    orca: bool,
    blocks: int,
    DT: float,
    DoubleIntegrator,
) -> None:
    """The results file: the three tables of ``benchmarks/speed/scaling.py``."""
    lines = [
        "# Scaling: the filter on crowds of 10 to 30,000 agents, against ORCA",
        "",
        f"Written by `python -m benchmarks.speed.scaling` in one process ({machine()}"
        + (
            ", pyrvo (ORCA, C++)"
            if orca
            else "; pyrvo not installed: `pip install -e .[baselines]`"
        )
        + f"). Each figure is the fastest of {blocks} alternating blocks of steps (other "
        "processes only ever slow a block down).",
        "",
        "## 1. Single-integrator crowd: filtered step per agent, ours against ORCA",
        "",
        "Ours: `SafetyFilter.filter` on plain arrays (input checks, neighbours, rows, exact"
        " solve) plus x += dt u, dt = 0.05, crowd defaults (R = 1 m, u_max = 2 m/s, gamma = 10)."
        " ORCA: pyrvo on the same starts and goals, agent radius R/2, max speed u_max,"
        " neighbour distance 5R, 10 neighbours, time horizon 2 s; its C++ `do_step` alone is"
        " timed (setting the preferred velocities from Python is not). Min distance: our"
        " smallest distance between two agents over every timed step (must be >= R).",
        "",
        "| N | steps a block | ours, theta equal [µs] | ORCA [µs] | ours / ORCA |"
        " ours, theta 1..10 [µs] | ORCA [µs] | ours / ORCA | min distance (equal, 1..10) [m] |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        o, o2 = r.get("orca"), r.get("orca_spread")
        lines.append(
            f"| {r['n']:,} | {r['steps']} | {r['ours_equal']:.2f} | "
            + (f"{o:.2f} | {r['ours_equal'] / o:.2f} |" if o else "— | — |")
            + f" {r['ours_spread']:.2f} | "
            + (f"{o2:.2f} | {r['ours_spread'] / o2:.2f} |" if o2 else "— | — |")
            + f" {r['ours_equal_min_distance']:.6f}, {r['ours_spread_min_distance']:.6f} |"
        )
    at = {r["n"]: r for r in rows}
    if 1000 in at and 30_000 in at:
        lines += [
            "",
            "Own cost at N = 30,000 over N = 1,000: theta equal "
            f"{at[30_000]['ours_equal'] / at[1000]['ours_equal']:.2f}x, theta 1..10 "
            f"{at[30_000]['ours_spread'] / at[1000]['ours_spread']:.2f}x.",
        ]
    lines += ["", *di_section(di, DT, DoubleIntegrator)]
    if big:
        lines += [
            "",
            "## 3. A 10,000-agent crowd, 1,000 filtered steps (each in a fresh process)",
            "",
            "Peak memory: the largest resident set sampled after the setup and after every step,"
            " minus the one after the imports (and numba's compilation). `BatchedEnv` keeps the"
            " (N, N) weight matrix of its observations; the filter on plain arrays needs none.",
            "",
            "| run | setup [s] | 1,000 steps [s] | min distance [m] | peak memory | per agent |",
            "|---|---|---|---|---|---|",
        ]
        for b in big:
            name = "BatchedEnv (scripted nominal)" if b["mode"] == "env" else "filter on arrays"
            lines.append(
                f"| {name} | {b['setup_s']:.1f} | {b['wall_s']:.1f} | {b['min_distance']:.6f} |"
                f" {b['peak_bytes'] / 2**20:,.1f} MiB | {b['peak_bytes'] / b['n'] / 1024:.2f} KiB |"
            )
    path.write_text("\n".join(lines) + "\n")
    print(path.read_text())
