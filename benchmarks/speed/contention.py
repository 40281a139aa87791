"""Speed under load: aggregate throughput of 1, 2 and 4 concurrent processes on this machine,
each stepping a workload with the library's defaults, against one quiet process with one thread.

Workloads (scripted move-to-goal actions, filter on):
- ``batched``: ``BatchedEnv("crowd")`` 16 agents x 256 envs (N x E, as ``env_speed.py``);
- ``crowd``: the filtered crowd at N = 1,000 (one env).

Settings: ``default`` (nothing set: the library's thread policy, ``docs/threads.md``) and
``pool`` (``RSVO_NUM_THREADS`` = the core count: the parallel kernels the library used by default
before). Each process warms up, then counts agent-steps for a fixed wall time; the aggregate is
their sum. Rounds alternate the settings' order; the reference (one process,
``RSVO_NUM_THREADS=1 NUMBA_NUM_THREADS=1``) runs in every round, and each ratio is taken against
its own round's reference. Also the kernel threshold: one solve of n independent QPs, one thread and
two, in one process (``sizes.PARALLEL_MIN_PROBLEMS``).

Writes ``benchmarks/results/contention.md``.

    python -m benchmarks.speed.contention [--seconds 8] [--rounds 2]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from benchmarks.harness import RESULTS, ROOT

# name: (envs, agents an env)
WORKLOADS = {"batched": (256, 16), "crowd": (1, 1000)}
CORES = os.cpu_count() or 1


def worker(workload: str, seconds: float) -> None:
    """One process: warm up, then step for ``seconds``; prints its agent-steps per second."""
    from rsvo_env.envs.vector import BatchedEnv

    e, n = WORKLOADS[workload]
    env = BatchedEnv("crowd", num_envs=e, num_agents=n, safety_filter=True, nominal="move_to_goal")
    env.reset(seed=0)
    for _ in range(20):
        env.step(env.nominal_actions())
    steps, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        env.step(env.nominal_actions())
        steps += 1
    print(json.dumps({"rate": steps * e * n / (time.perf_counter() - start)}))


def concurrent(workload: str, procs: int, seconds: float, env: dict[str, str]) -> float:
    """Aggregate agent-steps per second of ``procs`` processes started together."""
    cmd = [sys.executable, __file__, "--worker", workload, str(seconds)]
    running = [
        subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, text=True, cwd=ROOT)
        for _ in range(procs)
    ]
    rates = []
    for p in running:
        out, _ = p.communicate()
        if p.returncode != 0:
            raise RuntimeError(f"worker {workload} failed with {p.returncode}")
        rates.append(json.loads(out.strip().splitlines()[-1])["rate"])
    return float(sum(rates))


def settings() -> dict[str, dict[str, str]]:
    unset = ("RSVO_NUM_THREADS", "NUMBA_NUM_THREADS")
    base = {k: v for k, v in os.environ.items() if k not in unset}
    return {
        "reference": {**base, "RSVO_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1"},
        "default": base,
        "pool": {**base, "RSVO_NUM_THREADS": str(CORES)},
    }


def kernel_threshold(sizes=(64, 128, 256, 512, 1024, 4096), repeats: int = 200) -> list[tuple]:
    """Microseconds of one solve of n QPs (8 rows each), on one thread (the form the library
    takes for n there, ``docs/threads.md``) and with the pool (forced at every n: the threshold
    lowered to 0 for the measurement)."""
    from rsvo_env.qp import exact
    from rsvo_env.util import threads

    rng = np.random.default_rng(0)
    box = np.array([2.0, 2.0])
    rows = []
    keep, sizes.PARALLEL_MIN_PROBLEMS = sizes.PARALLEL_MIN_PROBLEMS, 0
    try:
        for n in sizes:
            qps = (
                rng.normal(size=(n, 2)),
                rng.normal(size=(n * 8, 2)),
                rng.uniform(0.1, 1.0, n * 8),
                np.arange(0, 8 * n + 1, 8, dtype=np.int64),
                -box,
                box,
            )
            times = {}
            for k in (1, CORES, 1, CORES):  # alternating, the second of each kept
                with threads.using(k):
                    exact.solve_csr(*qps)
                    t = time.perf_counter()
                    for _ in range(repeats):
                        exact.solve_csr(*qps)
                    times[k] = 1e6 * (time.perf_counter() - t) / repeats
            rows.append((n, times[1], times[CORES]))
    finally:
        sizes.PARALLEL_MIN_PROBLEMS = keep
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--worker", nargs=2, metavar=("WORKLOAD", "SECONDS"), help=argparse.SUPPRESS)
    ap.add_argument("--seconds", type=float, default=8.0)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--out", type=Path, default=RESULTS / "contention.md")
    args = ap.parse_args(argv)
    if args.worker:
        worker(args.worker[0], float(args.worker[1]))
        return 0
    envs = settings()
    results: dict[tuple, list[float]] = {}
    for r in range(args.rounds):
        for workload in WORKLOADS:
            ref = concurrent(workload, 1, args.seconds, envs["reference"])
            results.setdefault((workload, "reference", 1), []).append(ref)
            order = ("default", "pool") if r % 2 == 0 else ("pool", "default")
            for name in order:
                for procs in (1, 2, 4):
                    agg = concurrent(workload, procs, args.seconds, envs[name])
                    results.setdefault((workload, name, procs), []).append(agg / ref)
                    print(workload, name, procs, f"{agg:.0f}", f"{agg / ref:.2f}", flush=True)
    kernel = kernel_threshold()
    write(args.out, results, kernel, args)
    return 0


def write(path: Path, results: dict, kernel: list[tuple], args) -> None:
    lines = [
        "# Speed under load",
        "",
        f"Written by `python -m benchmarks.speed.contention --seconds {args.seconds:g} --rounds"
        f" {args.rounds}` on this machine ({CORES} cores, shared with whatever else ran). Each"
        " process steps its workload (scripted move-to-goal, filter on) for"
        f" {args.seconds:g} s after a warm-up; the aggregate is the sum of the processes'"
        " agent-steps per second. Ratio: the aggregate over one quiet process with one thread"
        " (`RSVO_NUM_THREADS=1 NUMBA_NUM_THREADS=1`) run in the same round; the worst of the"
        " rounds. `default`: nothing set (the library's policy, `docs/threads.md`); `pool`:"
        f" `RSVO_NUM_THREADS={CORES}`, the parallel kernels the library used by default before.",
        "",
        "| workload | reference [agent-steps/s] | setting | 1 process | 2 processes |"
        " 4 processes |",
        "|---|---|---|---|---|---|",
    ]
    for workload, (e, n) in WORKLOADS.items():
        ref = min(results[(workload, "reference", 1)])
        for name in ("default", "pool"):
            cells = [f"{min(results[(workload, name, p)]):.2f}x" for p in (1, 2, 4)]
            lines.append(
                f"| {workload} (N {n:,} x E {e}) | {ref:,.0f} | {name} | "
                + " | ".join(cells)
                + " |"
            )
    lines += [
        "",
        "## Kernel threshold",
        "",
        f"One `exact.solve_csr` of n QPs of 8 rows, microseconds, one thread against {CORES}"
        " threads, in one process (the parallel kernel below its threshold forced for the"
        " measurement). The library goes parallel (when given threads) from"
        " `sizes.PARALLEL_MIN_PROBLEMS` = 256.",
        "",
        f"| n | one thread [us] | {CORES} threads [us] | {CORES} threads / one |",
        "|---|---|---|---|",
    ]
    for n, serial, par in kernel:
        lines.append(f"| {n:,} | {serial:.1f} | {par:.1f} | {par / serial:.2f} |")
    path.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    sys.exit(main())
