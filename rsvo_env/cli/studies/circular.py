"""Circular game (paper, Sec. V-C, Figs. 5-7): six agents swap with the antipodal agent; the
deadlock onset, its resolution and completion under symmetric and asymmetric weights, and the
gains over random personality sets."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from rsvo_env.cli.episode import run
from rsvo_env.cli.studies import ALTERNATING, Plan
from rsvo_env.sim.metrics import completion_gain, resolution_gain


def steps_of(out: dict) -> tuple[int | None, int | None, int | None]:
    return out["deadlock_onset"], out["deadlock_resolved"], out["completed"]


def gains(sym: dict, asym: dict) -> tuple[float | None, float | None]:
    """Resolution and completion gains of a run against the symmetric one (None if unfinished)."""
    o_s, r_s, c_s = steps_of(sym)
    o_a, r_a, c_a = steps_of(asym)
    res = comp = None
    if o_s is not None and r_s is not None and o_a is not None and r_a is not None:
        res = resolution_gain(o_s, r_s, o_a, r_a)
    if c_s is not None and c_a is not None:
        comp = completion_gain(c_s, c_a)
    return res, comp


def random_theta_sets(seed: int, count: int) -> list[list[float]]:
    """Distinct integers 1..10 per set (the paper's protocol), from one seeded generator."""
    rng = np.random.default_rng(seed)
    return [
        rng.choice(np.arange(1, 11), 6, replace=False).astype(float).tolist() for _ in range(count)
    ]


# the paper's scripted controller (Sec. V-A), not the scenario's default R-ORCA
PAPER_NOMINAL = "move_to_goal"


def study(plan: Plan, progress: Callable, out_dir: Path) -> dict[str, Any]:
    """The alternating example (with GIFs), the same without the right-hand rule, and the random
    sets; the symmetric filter ignores theta, so one symmetric run serves every set."""
    sym, asym = (
        run(
            "circular_swap",
            weighting=w,
            theta=ALTERNATING,
            seed=plan.seed,
            gif=out_dir / f"circular_{w}.gif",
            nominal=PAPER_NOMINAL,
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
            nominal=PAPER_NOMINAL,
        )
        for w in ("symmetric", "asymmetric")
    }
    progress()
    g_res, g_comp = gains(sym, asym)
    n_small, n_large = plan.n_random_sets
    sets = random_theta_sets(plan.seed, max(n_small, n_large))
    per_set = []
    for theta in sets:
        per_set.append(run("circular_swap", theta=theta, seed=plan.seed, nominal=PAPER_NOMINAL))
        progress()
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
    collisions = sum(o["n_collision_steps"] for o in per_set)
    return {
        "runs": {"sym": sym, "asym": asym, "random": per_set[:n_small]},
        "no_rule_runs": no_rule,
        "sym": steps_of(sym),
        "asym": steps_of(asym),
        "resolution_gain": g_res,
        "completion_gain": g_comp,
        "no_rule": {w: steps_of(o) for w, o in no_rule.items()},
        "stats": stats,
        "random_collisions": collisions,
        "random_infeasible": sum(o["n_infeasible"] for o in per_set),
        "collisions": collisions + sym["n_collision_steps"] + asym["n_collision_steps"],
        "per_set": per_set,
        "sets": sets,
    }
