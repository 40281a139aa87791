"""Position swap (paper, Sec. V-A, Fig. 3): two agents swap corners under weights 0.8/0.2,
0.5/0.5 and 0.2/0.8, at two safety radii; who travels farther before they meet."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from rsvo_env.cli.episode import run
from rsvo_env.cli.studies import Plan, defaults
from rsvo_env.responsibility.svo import theta_for_weight

RADII = (1.0, 2.0)
WEIGHTS = (0.8, 0.5, 0.2)


def study(plan: Plan, progress: Callable) -> dict[str, Any]:
    """Per run: distances and mean speeds up to the meeting step (the right-hand rule first
    fires), the larger-omega agent's distance over the other's; and the runs themselves."""
    dt = defaults("position_swap")["dt"]
    runs, rows, ratios, by_radius = {}, [], [], {}
    for R in RADII:
        for w1 in WEIGHTS:
            out = run(
                "position_swap", theta=list(theta_for_weight(w1)), safety_radius=R, seed=plan.seed
            )
            progress()
            onset = out["deadlock_onset"]
            seg = out["trajectory"][: (onset or out["steps"]) + 1]
            d = np.linalg.norm(np.diff(seg, axis=0), axis=2).sum(axis=0)
            t = (onset or out["steps"]) * dt
            ego = 0 if w1 >= 0.5 else 1
            ratio = d[ego] / d[1 - ego]
            if w1 != 0.5:
                ratios.append(ratio)
                by_radius[R] = ratio
            runs[(R, w1)] = out
            rows.append(
                {
                    "R": R,
                    "w1": w1,
                    "distance": d,
                    "speed": d / t,
                    "ratio": ratio,
                    "onset": onset,
                    "completed": out["completed"],
                    "min_distance": out["min_distance"],
                    "collisions": out["n_collision_steps"],
                }
            )
    return {
        "rows": rows,
        "runs": runs,
        "ratio_min": min(ratios),
        "ratio_max": max(ratios),
        "ratio_by_radius": by_radius,
    }
