"""Microseconds per agent-QP: the exact solver against qpsolvers backends, in one process.

Writes ``benchmarks/results/solver_speed.md``. Run from a checkout:
``python -m benchmarks.speed.solver_speed`` (``--quick`` for a smaller run).

The reference backends solve one QP per call, so their cost per QP does not depend on the batch;
for batches above ``--ref-cap`` they are timed on the first ``--ref-cap`` problems of the batch.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import qpsolvers

from benchmarks.harness import RESULTS, machine
from rsvo_env.qp import exact, reference
from tests.support.instances import make_batch, stack

REFERENCES = ("clarabel", "daqp", "osqp")


def time_exact(args: tuple, repeats: int) -> float:
    exact.solve_batch(*args)  # compile / warm
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        exact.solve_batch(*args)
        best = min(best, time.perf_counter() - t0)
    return best / len(args[0]) * 1e6


def time_reference(instances: list[dict], solver: str) -> float:
    """The backend alone: one ``qpsolvers.solve_qp`` per QP with the reference's options."""
    P = 2.0 * np.eye(2)
    opts = {**reference.SOLVER_OPTIONS.get(solver, {}), "verbose": False}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.perf_counter()
        for p in instances:
            qpsolvers.solve_qp(
                P,
                -2.0 * p["nominal"],
                p["A"],
                p["b"],
                lb=p["lo"],
                ub=p["hi"],
                solver=solver,
                **opts,
            )
        return (time.perf_counter() - t0) / len(instances) * 1e6


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--ref-cap", type=int, default=1000)
    ap.add_argument("--out", type=Path, default=RESULTS / "solver_speed.md")
    args = ap.parse_args(argv)
    Ks = (1, 5, 20, 100)
    batches = (10, 1000) if args.quick else (10, 1000, 10000)
    cap = 200 if args.quick else args.ref_cap
    rng = np.random.default_rng(0)
    rows = []
    t_start = time.perf_counter()
    for K in Ks:
        for B in batches:
            inst = make_batch(rng, B, K, kinds=("random",))
            arrays = stack(inst)
            us = {"exact": time_exact(arrays, repeats=20 if B <= 1000 else 5)}
            for solver in REFERENCES:
                us[solver] = time_reference(inst[:cap], solver)
            rows.append((K, B, us))
            print(
                f"K={K:3d} batch={B:5d} " + " ".join(f"{k}={v:9.3f}us" for k, v in us.items()),
                flush=True,
            )
    wall = time.perf_counter() - t_start
    lines = [
        "# Solver speed: microseconds per agent-QP",
        "",
        f"Written by `python -m benchmarks.speed.solver_speed{' --quick' if args.quick else ''}` "
        f"in one process ({machine()}); wall time {wall:.0f} s.",
        "Instances: random feasible 2-D QPs with K half-planes and a box "
        "(tests/support/instances.py).",
        "`exact`: best of repeated batched calls (numba). Reference backends: one "
        "`qpsolvers.solve_qp` call per QP with the reference options (clarabel's tolerances "
        f"tightened), timed on min(batch, {cap}) problems.",
        "",
        "| K | batch | exact | clarabel | daqp | osqp | clarabel / exact | daqp / exact |"
        " osqp / exact |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for K, B, us in rows:
        e = us["exact"]
        lines.append(
            f"| {K} | {B} | {e:.3f} | {us['clarabel']:.1f} | {us['daqp']:.1f} | {us['osqp']:.1f}"
            f" | {us['clarabel'] / e:,.0f}x | {us['daqp'] / e:,.0f}x | {us['osqp'] / e:,.0f}x |"
        )
    target = next(us for K, B, us in rows if K == 20 and B == 1000)
    r_cl, r_dq = target["clarabel"] / target["exact"], target["daqp"] / target["exact"]
    lines += [
        "",
        f"Target at K = 20, batch 1000: exact >= 1,000x faster than clarabel (measured "
        f"{r_cl:,.0f}x: {'met' if r_cl >= 1000 else 'NOT met'}) and >= 20x faster than daqp "
        f"(measured {r_dq:,.0f}x: {'met' if r_dq >= 20 else 'NOT met'}).",
        "",
    ]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(lines))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
