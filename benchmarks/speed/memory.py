"""Memory and pairs of the filtered crowd step against the personalities: extreme scores must
cost their own rows, not O(N^2).

    python -m benchmarks.speed.memory            # writes benchmarks/results/memory.md

For each crowd size and theta set: the pairs the search examines, the bytes of the rows kept
(stored by agent) and of the search's floors, the resident memory the env holds in a fresh
process (after a small crowd compiled the kernels, so compiling is not counted), and the step
time as a ratio to theta 1..10 measured in the same process, alternating blocks.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from benchmarks.harness import RESULTS, ROOT, machine

CASES = {
    "theta 1..10": {},
    "+ one at 1e-7": {0: 1e-7},
    "+ one at 100": {1: 100.0},
    "+ one at 1e-7, one at 100": {0: 1e-7, 1: 100.0},
}


def scores(n: int, case: str) -> np.ndarray:
    theta = np.random.default_rng(n).uniform(1.0, 10.0, n)
    for i, value in CASES[case].items():
        theta[i] = value
    return theta


def footprint(n: int, case: str) -> dict:
    """In this process: pairs and bytes of one filter call on a crowd of n."""
    from rsvo_env.filter.safety import FilterConfig, SafetyFilter
    from rsvo_env.responsibility import pair_weights
    from rsvo_env.scenarios import Crowd

    x = Crowd(num_agents=n, spacing_factor=1.0)._spread(np.random.default_rng(n))
    theta = scores(n, case)
    flt = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=1.0, u_max=2.0, dt=0.01))
    # every agent at full speed in a random direction (at rest no row beyond the safe
    # distance can bind: rsvo_env.filter.projection_disk)
    angle = np.random.default_rng(0).uniform(0.0, 2.0 * np.pi, n)
    nominal = 2.0 * np.stack([np.cos(angle), np.sin(angle)], axis=-1)
    rows = flt.filter(x, nominal, theta).rows
    row_bytes = sum(
        getattr(rows, f).nbytes
        for f in (
            "flat_A",
            "flat_b",
            "offsets",
            "flat_neighbor",
            "flat_h",
            "pair_h",
            "flat_unrecoverable",
            "flat_capped",
        )
    )
    floor_bytes = sum(a.nbytes for a in pair_weights.floor_of(theta[None], "asymmetric"))
    return {
        "pairs": int(rows.n_pairs),
        "rows": int(len(rows.flat_b)),
        "widest": int(rows.counts.max()),
        "row_MB": row_bytes / 1e6,
        "floor_MB": floor_bytes / 1e6,
    }


def resident_child(n: int, case: str) -> None:
    """Run in a fresh process: print the resident memory (MB) an n-agent env adds (built, reset,
    five steps) to a process that compiled every kernel on a small crowd first."""
    from rsvo_env.envs.vector import BatchedEnv

    # compile every kernel on a small crowd of the same kind, so what is measured is the crowd's own
    small = BatchedEnv("crowd", num_envs=1, nominal="move_to_goal", num_agents=200)
    small.reset(seed=0, options={"theta": scores(200, case)})
    small.step(small.nominal_actions())
    before = resident_mb()
    env = BatchedEnv("crowd", num_envs=1, nominal="move_to_goal", num_agents=n)
    env.reset(seed=0, options={"theta": scores(n, case)})
    for _ in range(5):
        env.step(env.nominal_actions())
    print(json.dumps({"resident_added_MB": resident_mb() - before}))


def resident_mb() -> float:
    """This process's resident memory now (the peak would be the compiler's)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def resident(n: int, case: str) -> float:
    code = f"from benchmarks.speed import memory; memory.resident_child({n}, {case!r})"
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True
    )
    return json.loads(out.stdout.strip().splitlines()[-1])["resident_added_MB"]


def step_ratios(n: int, blocks: int = 3, steps: int = 3) -> dict[str, float]:
    """Step time of each case over theta 1..10's, alternating blocks in this process."""
    from rsvo_env.envs.vector import BatchedEnv

    envs = {}
    for case in CASES:
        env = BatchedEnv(
            "crowd", num_envs=1, num_agents=n, theta_range=(1.0, 10.0), nominal="move_to_goal"
        )
        env.reset(seed=0, options={"theta": scores(n, case)})
        env.step(env.nominal_actions())
        envs[case] = env
    times = {case: [] for case in CASES}
    for _ in range(blocks):
        for case, env in envs.items():
            start = time.perf_counter()
            for _ in range(steps):
                env.step(env.nominal_actions())
            times[case].append((time.perf_counter() - start) / steps)
    base = np.median(times["theta 1..10"])
    return {case: float(np.median(t) / base) for case, t in times.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[2000, 4000, 8000, 10000])
    ap.add_argument("--out", type=Path, default=RESULTS / "memory.md")
    args = ap.parse_args()
    lines = [
        "# Memory and pairs against the personalities",
        "",
        "Command: `python -m benchmarks.speed.memory`. Crowd of N agents (spacing 1 R, R = 1,",
        "u_max 2,",
        "gamma 10), theta drawn from U(1, 10), then one agent set to 1e-7 and/or one to 100.",
        "Rows and floors: bytes of the filter's rows kept (stored by agent) and of the pair",
        "search's floors; resident added: the memory the N-agent env holds (built, reset, five",
        "steps) in a fresh process whose kernels a 200-agent crowd compiled first; step time:",
        "the env step against theta 1..10's, in one process, alternating blocks.",
        f"Machine: {machine()}.",
        "",
        "| N | theta | pairs examined | rows kept | widest agent | rows + floors (MB) "
        "| resident added (MB) | step time |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for n in args.sizes:
        ratios = step_ratios(n)
        for case in CASES:
            f = footprint(n, case)
            lines.append(
                f"| {n:,} | {case} | {f['pairs']:,} | {f['rows']:,} | {f['widest']:,} | "
                f"{f['row_MB'] + f['floor_MB']:.2f} | {resident(n, case):.0f} | "
                f"{ratios[case]:.2f}x |"
            )
            print(lines[-1], flush=True)
    args.out.write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
