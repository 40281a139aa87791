"""Crowds that finish: the scripted controller behind the filter (R-ORCA, ``docs/liveness.md``)
against ORCA (pyrvo, the ``baselines`` extra) on the same starts and goals.

``crowd`` (R = 1 m, u_max = 2 m/s, k = 2, dt = 0.05, gamma = 20 so that gamma dt = 1 as in the
training configs, theta drawn from 1..10 per episode):
for each N and seed, ours through ``BatchedEnv`` (the filter on, its scripted nominal), ORCA
with agent radius R/2, max speed u_max, neighbour distance 5R, 10 neighbours, horizon 2 s and
the same move-to-goal preferred velocity. Per run: the share of agents that have reached their
goals step by step, the makespan (the step the last did), the closest pair over the run. Also
the circular swap (6 to 64 agents) and the doorway, ours alone, with the paper's 6-agent
figures beside them, the weighting's effect (egoists first; asymmetric against symmetric), and
move-to-goal (today's controller, kept by name) at N = 100.

Writes ``benchmarks/results/liveness.md`` and ``liveness.png``.

    python -m benchmarks.studies.liveness [--quick] [--circular-only] [--symmetric-only]
        [--held-out] [--big] [--diagnose] [--learned RUN]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from benchmarks.harness import RESULTS
from benchmarks.reports.liveness_report import (
    BIG_CAP,
    BIG_HEADING,
    BIG_SEEDS,
    DIAGNOSIS_CAP,
    DIAGNOSIS_HEADING,
    DT,
    HELD_OUT_HEADING,
    HELD_OUT_SEEDS,
    LEARNED_HEADING,
    SYMMETRIC_HEADING,
    big_section,
    circular_section,
    diagnosis_section,
    held_out_section,
    plot,
    replace_section,
    seconds_cell,
    symmetric_section,
    write,
)
from rsvo_env.control import rorca
from rsvo_env.control.nominal import move_to_goal
from rsvo_env.control.rorca.controller import ROUTED, UNROUTED
from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.scenarios import paired_theta
from rsvo_env.util.neighbors import nearest_distance

GAMMA = 20.0  # gamma dt = 1, as the training configs run the crowd
ROTATIONS = 10  # circular swaps, each turned by a random angle
# what holds the crowd of 10,000 back (issue 45): the crowd's settings changed one at a time
NO_TURN = {"rorca_route": False, "deadlock_resolution": "none"}
# ORCA behind the filter: no routing, no right-hand rule, no goal rule, ORCA's split and horizon
BARE = {**NO_TURN, "rorca_goal_reach": 0.0, "weighting": "symmetric", "rorca_tau": 2.0}
BARE_LABEL = (
    "no routing, no right-hand rule, the goal rule off, the symmetric weighting, horizon"
    " 2 s: ORCA's controller"
)
DIAGNOSIS = (
    ("R-ORCA routed behind the filter (the crowd table's setting)", {}),
    ("routing off (the right-hand rule turns R-ORCA's velocity again)", {"rorca_route": False}),
    ("routing off, no right-hand rule", NO_TURN),
    ("routing off, R-ORCA's general rules as before routing (horizon"
     f" {UNROUTED['rorca_tau']:g} s, bodies {UNROUTED['rorca_pad']:g} R, the goal rule after"
     f" {UNROUTED['rorca_goal_hold']:g} s within {UNROUTED['rorca_goal_reach']:g} radii)",
     UNROUTED),
    ("the goal rule off (`rorca_goal_reach = 0`)", {"rorca_goal_reach": 0.0}),
    (f"the goal rule after {rorca.HOLD_SECONDS:g} s, not {ROUTED['rorca_goal_hold']:g} s",
     {"rorca_goal_hold": rorca.HOLD_SECONDS}),
    (f"R-ORCA's horizon 2 s, not {ROUTED['rorca_tau']:g} s", {"rorca_tau": 2.0}),
    (f"R-ORCA's bodies 1.05 R, not {ROUTED['rorca_pad']:g} R", {"rorca_pad": 1.05}),
    ("the symmetric weighting", {"weighting": "symmetric"}),
    ("no filter", {"safety_filter": False}),
    ("the symmetric weighting, no filter", {"weighting": "symmetric", "safety_filter": False}),
    (BARE_LABEL, BARE),
    (BARE_LABEL + ", no filter", {**BARE, "safety_filter": False}),
)  # fmt: skip
# run on to 450 s: without R-ORCA's rules and the R-SVO split, does the filtered crowd finish?
DIAGNOSIS_LONG = ((BARE_LABEL, BARE),)


def ours(n: int, seed: int, cap: int, scenario: str = "crowd", **kw) -> dict:
    """One episode of ``scenario`` under its scripted controller, filtered unless
    ``safety_filter=False``: arrivals by step."""
    filtered = kw.pop("safety_filter", True)
    if not filtered:  # the filter's parameters have no owner without it
        kw.pop("gamma", None)
    env = BatchedEnv(scenario, num_envs=1, safety_filter=filtered, num_agents=n, max_steps=cap,
                     dt=kw.pop("dt", DT), **kw)  # fmt: skip
    env.reset(seed=seed)
    start = env.sim.state.positions[0].copy(), env.sim.state.goals[0].copy()
    arrived, closest = [], np.inf
    arrival = np.full(n, -1)  # read from the infos: an episode that ends resets the metrics
    theta = env.sim.state.theta[0].copy()
    for step in range(1, cap + 1):
        _, _, term, trunc, info = env.step(env.nominal_actions())
        closest = min(closest, float(info["min_distance"].min()))
        arrived.append(int(info["episode_arrived"][0]))
        arrival = np.where((arrival < 0) & info["at_goal"][0], step, arrival)
        if arrived[-1] == n or term.any() or trunc.any():
            break
    return {"arrived": np.array(arrived) / n, "makespan": _makespan(arrived, n),
            "closest": closest, "start": start, "theta": theta, "arrival": arrival}  # fmt: skip


def orca(start: np.ndarray, goals: np.ndarray, cap: int, R=1.0, u_max=2.0, k=2.0, tol=0.05):
    """ORCA (pyrvo) from the same starts to the same goals, the same preferred velocity."""
    import pyrvo

    n = len(start)
    sim = pyrvo.RVOSimulator()
    sim.set_time_step(DT)
    sim.set_agent_defaults(5.0 * R, 10, 2.0, 2.0, R / 2, u_max)
    for x in start:
        sim.add_agent((float(x[0]), float(x[1])))
    reached = np.zeros(n, dtype=bool)
    arrived, closest = [], np.inf
    for _ in range(cap):
        pos = np.array([(q.x, q.y) for q in map(sim.get_agent_position, range(n))])
        u = move_to_goal(pos, goals, k, u_max)
        for i in range(n):
            sim.set_agent_pref_velocity(i, (float(u[i, 0]), float(u[i, 1])))
        sim.do_step()
        pos = np.array([(q.x, q.y) for q in map(sim.get_agent_position, range(n))])
        closest = min(closest, float(nearest_distance(pos[None]).min()))
        reached |= np.linalg.norm(pos - goals, axis=1) < tol
        arrived.append(int(reached.sum()))
        if reached.all():
            break
    return {"arrived": np.array(arrived) / n, "makespan": _makespan(arrived, n),
            "closest": closest}  # fmt: skip


def _makespan(arrived: list[int], n: int) -> int | None:
    return len(arrived) if arrived and arrived[-1] == n else None


def diagnosis(configs=DIAGNOSIS, n: int = 10_000, seed: int = 0, cap: int = DIAGNOSIS_CAP,
              with_orca: bool = True) -> list[dict]:  # fmt: skip
    """The crowd of ``n`` under each of ``configs`` (R-ORCA's rules, the weighting, the filter
    taken away one at a time), and ORCA on the same starts and goals."""
    rows = []
    for label, kw in configs:
        r = ours(n, seed, cap, **{"theta_range": (1.0, 10.0), "gamma": GAMMA, **kw})
        rows.append({"label": label, "ours": r})
        print("diagnosis", label, r["arrived"][-1], r["closest"], flush=True)
    if not with_orca:
        return rows
    return [*rows, {"label": "ORCA (pyrvo)", "ours": orca(*rows[0]["ours"]["start"], cap)}]


def crowds(sizes, seeds, cap, weighting: str = "asymmetric", **kw) -> list[dict]:
    rows = []
    for n in sizes:
        for seed in seeds:
            a = ours(n, seed, cap, theta_range=(1.0, 10.0), gamma=GAMMA, weighting=weighting,
                     **kw)  # fmt: skip
            b = orca(*a["start"], cap)
            rows.append({"n": n, "seed": seed, "ours": a, "orca": b})
            print(n, seed, a["arrived"][-1], a["makespan"], b["arrived"][-1], b["makespan"],
                  a["closest"], b["closest"], flush=True)  # fmt: skip
    return rows


def circular(sizes, cap, nominal: str = "rorca") -> list[dict]:
    """The circular swap under the scripted controller ``nominal``, theta 2 and 1 as the
    paper's game sets them (``paired_theta``: alternating, every agent's antipode of the other
    kind), both weightings."""
    rows = []
    for n in sizes:
        theta = paired_theta(n)
        radius = max(5.0, 0.6 * n / np.pi)  # room for n bodies on the circle
        out = {}
        for weighting in ("asymmetric", "symmetric"):
            r = ours(n, 0, cap, "circular_swap", theta=theta, circle_radius=radius,
                     weighting=weighting, dt=0.01, nominal=nominal)  # fmt: skip
            egoist = np.array(theta) < max(theta)
            out[weighting] = r
            out[weighting + "_ego"] = float(r["arrival"][egoist].mean())
            out[weighting + "_alt"] = float(r["arrival"][~egoist].mean())
            out[weighting + "_rotated"] = rotated(n, theta, radius, weighting, cap, nominal)
        rows.append({"n": n, "nominal": nominal, **out})
        print("circular", n, out["asymmetric"]["makespan"], out["symmetric"]["makespan"],
              flush=True)  # fmt: skip
    return rows


def circular_runs(sizes) -> list[dict]:
    """R-ORCA's circular swaps of ``sizes``, then the paper's own 6-agent game under the
    paper's controller (move-to-goal with the right-hand rule) as the reference."""
    return [*circular(sizes, 6000), *circular((6,), 6000, nominal="move_to_goal")]


def rotated(
    n: int, theta: list, radius: float, weighting: str, cap: int, nominal: str = "rorca"
) -> dict:
    """The circular swap in ``ROTATIONS`` envs, each circle turned by a random angle (the
    envs' generators, seed 0): the mean makespan and the mean arrival step of the egoists and
    of the altruists over every rotation (a single layout's order of arrival can turn on a
    tie, its symmetry broken by rounding)."""
    env = BatchedEnv("circular_swap", num_envs=ROTATIONS, safety_filter=True, num_agents=n,
                     max_steps=cap, dt=0.01, theta=theta, circle_radius=radius,
                     weighting=weighting, random_rotation=True, nominal=nominal)  # fmt: skip
    env.reset(seed=0)
    arrival = np.full((ROTATIONS, n), -1)  # first arrivals: an env that ends starts anew
    closest = np.inf
    for step in range(1, cap + 1):
        _, _, _, trunc, info = env.step(env.nominal_actions())
        closest = min(closest, float(info["min_distance"].min()))
        arrival = np.where((arrival < 0) & info["at_goal"], step, arrival)
        if (arrival >= 0).all() or trunc.any():
            break
    egoist = np.array(theta) < max(theta)
    done = (arrival >= 0).all(axis=1)  # the means are over the layouts that finished
    kept = arrival[done]
    return {"finished": int(done.sum()), "makespan": float(kept.max(axis=1).mean()),
            "ego": float(kept[:, egoist].mean()), "alt": float(kept[:, ~egoist].mean()),
            "closest": closest}  # fmt: skip


def learned(run: Path) -> list[str]:
    """The learned residual of ``run`` (trained on the crowd with R-ORCA under it) evaluated at
    the size it was trained at and in crowds of 100 and 1,000, beside the scripted controller on
    the same seeds (``rsvo_env.training.evaluate`` with ``--set env.num_agents=N``)."""
    from rsvo_env.training.evaluate import evaluate_loaded, load_model

    model = run / "best_model.zip"
    lines = [
        LEARNED_HEADING,
        "",
        f"Written by `python -m benchmarks.studies.liveness --learned {run}` after"
        f" `python -m rsvo_env.training.train --scenario crowd --set env.nominal=rorca"
        f" --set stall_gate=5 --set validation.episodes=100 --seed 0 --out {run}`: the residual"
        " policy trained on crowds of 12 (the config `training/configs/crowd.yaml`: dt 0.1,"
        " gamma dt = 1, theta 1..10) with R-ORCA under it and a stall gate of 5 s (an agent"
        " that has come no closer"
        " to its goal for 5 s follows R-ORCA alone until it does), its validation-best model"
        " evaluated unchanged in larger crowds (its observation is local), seeds 1000 and up,"
        " against the scripted controller (R-ORCA, a zero residual) on the same seeds. Success:"
        " every agent at its goal within the cap. Residual acting: the share of agent-steps"
        " (agents not yet at their goals) in which the policy's residual was not gated off.",
        "",
        "| N | episodes | cap [s] | success, policy / scripted | agents arrived, policy /"
        " scripted | completion [s], policy / scripted | collisions | closest pair [m] |"
        " infeasible steps | residual acting |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for n, episodes, cap in ((12, 100, 1000), (100, 100, 1000), (1000, 20, 3000)):
        policy, cfg = load_model(model, [f"env.num_agents={n}", f"validation.max_steps={cap}"])
        r = evaluate_loaded(policy, cfg, model, episodes, 1000, compare_scripted=True)
        a, b = r["policy"], r["scripted"]
        lines.append(
            f"| {n:,} | {episodes} | {cap * cfg['env']['dt']:.0f} | {100 * a['success_rate']:.0f} %"
            f" / {100 * b['success_rate']:.0f} % | {100 * a['arrived']:.1f} % /"
            f" {100 * b['arrived']:.1f} % | {seconds_cell(a)} / {seconds_cell(b)}"
            f" | {a['collisions']} / {b['collisions']}"
            f" | {min(a['min_distance'], b['min_distance']):.4f}"
            f" | {a['infeasible']} / {b['infeasible']} | {100 * a['residual_share']:.0f} % |"
        )
        print("learned", n, a["success_rate"], b["success_rate"], flush=True)
    return [*lines, ""]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="N = 100, 2 seeds")
    ap.add_argument(
        "--big",
        action="store_true",
        help="run the crowd of 10,000 alone, replacing its section in --out",
    )
    ap.add_argument(
        "--diagnose",
        action="store_true",
        help="run the crowd of 10,000 for 100 s with the routing, R-ORCA's rules, the weighting"
        " and the filter changed one at a time, replacing its section in --out",
    )
    ap.add_argument("--out", type=Path, default=RESULTS / "liveness.md")
    ap.add_argument(
        "--circular-only",
        action="store_true",
        help="rerun the circular swap alone, replacing its section in --out",
    )
    ap.add_argument(
        "--symmetric-only",
        action="store_true",
        help="rerun the crowds of 1,000 under the symmetric weighting alone, replacing their"
        " section in --out",
    )
    ap.add_argument(
        "--held-out",
        action="store_true",
        help="run crowds of 1,000 on seeds 10 to 19 (not the crowd table's) alone, replacing"
        " their section in --out",
    )
    ap.add_argument(
        "--learned",
        type=Path,
        metavar="RUN",
        help="evaluate the residual policy of a training run at 12, 100 and 1,000 agents alone,"
        " replacing its section in --out",
    )
    args = ap.parse_args(argv)
    if args.learned:
        section = learned(args.learned)
        replace_section(args.out, LEARNED_HEADING, section, "## Circular swap")
        return 0
    if args.symmetric_only:
        rows = crowds((1000,), range(10), 4000, weighting="symmetric")
        replace_section(args.out, SYMMETRIC_HEADING, symmetric_section(rows), "## Circular swap")
        return 0
    if args.held_out:
        rows = crowds((1000,), HELD_OUT_SEEDS, 4000)
        replace_section(args.out, HELD_OUT_HEADING, held_out_section(rows), "## Circular swap")
        return 0
    if args.circular_only:
        section = circular_section(circular_runs((6, 12, 24, 64)))
        replace_section(args.out, "## Circular swap", [*section, ""], "## Other runs")
        return 0
    if args.diagnose:
        long = diagnosis(DIAGNOSIS_LONG, cap=BIG_CAP, with_orca=False)
        section = diagnosis_section(diagnosis(), long)
        replace_section(args.out, DIAGNOSIS_HEADING, section, "## Crowd of 1,000, symmetric")
        return 0
    if args.big:
        rows = crowds((10_000,), BIG_SEEDS, BIG_CAP)
        replace_section(args.out, BIG_HEADING, big_section(rows), "## Circular swap")
        plot(rows, args.out.with_name("liveness_10000.png"))
        return 0
    seeds = range(2) if args.quick else range(10)
    sizes = (100,) if args.quick else (100, 1000)
    rows = crowds(sizes, seeds, 4000)
    circ = circular_runs((6, 12) if args.quick else (6, 12, 24, 64))
    extra = {
        "crowd N = 100, seed 0, move-to-goal (today's controller, kept by name)":
            ours(100, 0, 4000, nominal="move_to_goal", theta_range=(1.0, 10.0), gamma=GAMMA),
        "crowd N = 100, seed 0, the scenario's gamma (10, gamma dt = 0.5)":
            ours(100, 0, 4000, theta_range=(1.0, 10.0)),
        "doorway (8 agents), seed 0": ours(8, 0, 4000, "doorway"),
        "doorway (16 agents), seed 0": ours(16, 0, 4000, "doorway"),
    }  # fmt: skip
    write(args.out, rows, circ, extra, args.quick)
    plot(rows, args.out.with_suffix(".png"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
