"""Env step cost: agent-steps per second for ``crowd`` at N in {6, 100, 1000}, bare and filtered.

Writes ``benchmarks/results/env_speed.md``. Each row also gives the ratio to a reference run in
the same process: the bare numpy work every step must do at least (the Euler update of N agents
plus one nearest-neighbour query, the collision signal), timed on the same states.

    python benchmarks/env_speed.py [--seconds 3]
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

import rsvo_env
import wrappers
from rsvo_env.neighbors import nearest_distance

ROOT = Path(__file__).resolve().parents[1]


def env_rate(n: int, filtered: bool, seconds: float) -> tuple[float, float]:
    env = rsvo_env.parallel_env("crowd", num_agents=n)
    if filtered:
        env = wrappers.RCBFSafetyFilter(env)
    env.reset(seed=0)
    actions = env.unwrapped.nominal_actions()
    env.step(actions)  # warm (numba compile, caches)
    steps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        if not env.agents:
            env.reset()
        env.step(env.unwrapped.nominal_actions())
        steps += 1
    elapsed = time.perf_counter() - t0
    return n * steps / elapsed, elapsed / steps * 1e3


def reference_rate(n: int, seconds: float) -> float:
    env = rsvo_env.parallel_env("crowd", num_agents=n)
    env.reset(seed=0)
    x = env.unwrapped.world.positions.copy()
    u = env.unwrapped.nominal_controls()
    steps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        x = x + 0.01 * u
        nearest_distance(x)
        steps += 1
    return n * steps / (time.perf_counter() - t0)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seconds", type=float, default=3.0)
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "env_speed.md")
    args = ap.parse_args(argv)
    lines = [
        "# Env step cost: `crowd`, scripted nominal actions",
        "",
        f"Written by `python benchmarks/env_speed.py` in one process ({platform.machine()}, "
        f"Python {platform.python_version()}, numpy {np.__version__}), about {args.seconds:g} s "
        "a row. Reference: x += dt u plus one nearest-neighbour query on the same agents.",
        "",
        "| N | variant | agent-steps/s | ms per env step | reference agent-steps/s |"
        " env / reference |",
        "|---|---|---|---|---|---|",
    ]
    for n in (6, 100, 1000):
        ref = reference_rate(n, args.seconds)
        for filtered in (False, True):
            rate, ms = env_rate(n, filtered, args.seconds)
            name = "filtered (RCBFSafetyFilter, exact)" if filtered else "bare env"
            lines.append(
                f"| {n} | {name} | {rate:,.0f} | {ms:.3f} | {ref:,.0f} | {rate / ref:.3f} |"
            )
            print(lines[-1], flush=True)
    lines.append("")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(lines))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
