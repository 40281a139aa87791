"""What agents of their own size and the unicycle cost the filter, as ratios in one process.

* heterogeneous radii (0.2-2) and per-agent u_max against equal bodies, same crowd, N = 10,000;
* the unicycle (look-ahead point, rows turned into body frames) against the single integrator
  on the same positions, per agent-step, N = 1,000 and 10,000.

Timed in alternating blocks (best of each), so load from other processes hits both sides alike.
Writes ``benchmarks/results/bodies_speed.md``. Run from a checkout:
``python -m benchmarks.speed.bodies_speed`` (``--quick`` for N = 2,000 only).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from benchmarks.harness import ROOT, alternate, machine
from rsvo_env.filter.safety import FilterConfig, SafetyFilter


def crowd(n: int, seed: int = 0):
    """A dense crowd on a jittered grid (spacing 4.5, radii up to 2), goals a shuffle."""
    rng = np.random.default_rng(seed)
    side = int(np.ceil(np.sqrt(n)))
    grid = np.stack(np.meshgrid(np.arange(side), np.arange(side)), -1).reshape(-1, 2)[:n]
    x = (grid + rng.uniform(-0.05, 0.05, (n, 2))) * 4.5
    goals = x[rng.permutation(n)]
    d = goals - x
    nominal = 2.0 * d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-9)
    return x, nominal, rng.uniform(0.0, 10.0, n), rng.uniform(0.2, 2.0, n), rng.uniform(0.5, 3, n)


def measure(n: int, si: SafetyFilter, uni: SafetyFilter, blocks: int) -> dict[str, float]:
    """Best times of equal bodies, heterogeneous bodies and unicycles on one crowd of n."""
    x, nominal, theta, radii, u_max = crowd(n)
    headings = np.arctan2(nominal[:, 1], nominal[:, 0])
    equal_r = np.full(n, radii.mean())  # the same mean size
    ahead = np.c_[np.full(n, 2.0), np.zeros(n)]
    return alternate(
        {
            "equal": lambda: si.filter(x, nominal, theta, radii=equal_r),
            "hetero": lambda: si.filter(x, nominal, theta, radii=radii, u_max=u_max),
            "uni": lambda: uni.filter(x, ahead, theta, headings=headings, radii=equal_r),
        },
        blocks,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--blocks", type=int, default=5)
    parser.add_argument("--out", default=str(ROOT / "benchmarks/results/bodies_speed.md"))
    args = parser.parse_args()
    sizes = (2000,) if args.quick else (1000, 10000)
    si = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=2.0, u_max=3.0, dt=0.05))
    uni = SafetyFilter(
        FilterConfig(dynamics="unicycle", lookahead=0.2, w_max=2.0, u_max=3.0, gamma=10.0, dt=0.05)
    )
    lines = [
        "# Bodies of their own size and the unicycle: cost ratios",
        "",
        f"`python -m benchmarks.speed.bodies_speed`, {machine()}, "
        f"best of {args.blocks} alternating blocks, the filter alone (one call = one step).",
        "",
        "| N | equal bodies (ms) | radii 0.2-2 and u_max 0.5-3 (ms) | ratio | single integrator "
        "(ms) | unicycle (ms) | ratio |",
        "|---|---|---|---|---|---|---|",
    ]
    for n in sizes:
        t = measure(n, si, uni, args.blocks)
        lines.append(
            f"| {n:,} | {t['equal'] * 1e3:.1f} | {t['hetero'] * 1e3:.1f} | "
            f"{t['hetero'] / t['equal']:.2f} | {t['equal'] * 1e3:.1f} | {t['uni'] * 1e3:.1f} | "
            f"{t['uni'] / t['equal']:.2f} |"
        )
        print(lines[-1], flush=True)
    lines += [
        "",
        "The unicycle is timed on the same positions, its look-ahead points 0.2 ahead and each "
        "body enlarged by that much, its nominal full speed ahead.",
    ]
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
