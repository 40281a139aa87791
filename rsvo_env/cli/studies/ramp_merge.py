"""Ramp merge (paper, Sec. V-B, Fig. 4): two double-integrator vehicles merge; who goes first,
under three splits of the pair condition and two barriers, over merge angles and gains."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from rsvo_env.cli.episode import run
from rsvo_env.cli.studies import Plan, defaults

CASES = {
    "equal theta": [1.0, 1.0],
    "V2 more altruistic": [1.0, 4.0],
    "V2 more egoistic": [4.0, 1.0],
}
SPLITS = ("capability", "sign_aware", "paper")
BARRIERS = ("braking", "hocbf")
# the designs the figures show: the paper's split and ours, under the paper's barrier
FIGURE_DESIGNS = (("capability", "braking"), ("paper", "braking"))


def first_step(trajectory: np.ndarray, agent: int, y: float) -> int | None:
    """First step at which the agent is at or past ``y``."""
    hit = np.nonzero(trajectory[:, agent, 1] >= y)[0]
    return int(hit[0]) if len(hit) else None


def first_through(t: list[int | None]) -> str:
    if t[0] == t[1]:
        return "tie"
    return "V1" if (t[1] is None or (t[0] is not None and t[0] < t[1])) else "V2"


def study(plan: Plan, progress: Callable) -> dict[str, Any]:
    """Per design (split, barrier): runs, how often the egoist merges first, runs below the safety
    distance, the worst minimum distance, infeasible agent-steps; the default-setting detail."""
    p = defaults("ramp_merge")
    merge_y, safe = p["merge_point"][1], p["safety_radius"]
    summary: dict[Any, Any] = {}
    detail: list[Any] = []
    figure_runs: dict[tuple[str, str], Any] = {}
    for split in SPLITS:
        for barrier in BARRIERS:
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
                    for case, theta in CASES.items():
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
                        t = [first_step(out["trajectory"], i, merge_y) for i in range(2)]
                        first = first_through(t)
                        agg["runs"] += 1
                        agg["unsafe"] += int(out["min_distance"] < safe)
                        agg["worst"] = min(agg["worst"], out["min_distance"])
                        agg["infeasible"] += out["n_infeasible"]
                        if theta[0] != theta[1]:
                            egoist = "V1" if theta[0] < theta[1] else "V2"
                            agg["unequal"] += 1
                            agg["egoist_first"] += int(first == egoist)
                        if angle == p["lane_angle_deg"] and gamma == p["gamma"]:
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
                            if (split, barrier) in FIGURE_DESIGNS:
                                figure_runs[(split, case)] = out
    return {
        "summary": summary,
        "detail": detail,
        "figure_runs": figure_runs,
        "capability": summary[("capability", "braking")],
        "paper": summary[("paper", "braking")],
    }
