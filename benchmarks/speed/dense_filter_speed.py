"""Where the compiled all-pairs filter pass pays: it against the general path, per crowd size.

For each N, one crowd (the ``crowd`` scenario's starts and goals, move-to-goal nominal, theta
equal or 1..10) is stepped by the filter on plain arrays; every step is filtered twice on the
same state, by the dense pass (``solvers.dense``, every pair) and by the general path (grid
pair search, row packing, batched solve; forced with ``with_rows=True``), alternating blocks,
the best of ``--repeats``. The two must agree bit for bit (checked here too). The size where
the dense pass stops winning is ``sizes.COMPILED_FILTER_MAX_AGENTS``. Writes
``benchmarks/results/dense_filter_speed.md``.

    python -m benchmarks.speed.dense_filter_speed [--repeats 5]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from benchmarks.harness import RESULTS, machine
from rsvo_env.control.nominal import move_to_goal
from rsvo_env.filter import dense
from rsvo_env.filter.config import FilterConfig
from rsvo_env.filter.safety import SafetyFilter
from rsvo_env.scenarios import Crowd
from rsvo_env.util import sizes

SIZES = (32, 64, 100, 150, 200, 256, 300, 350, 512)
DT = 0.05


def states(n: int, spread: bool, steps: int) -> tuple[SafetyFilter, list, np.ndarray]:
    """The filter and ``steps`` (positions, nominal) states of one crowd run."""
    sc = Crowd(num_agents=n)
    x, _, goals = sc.initial_state(np.random.default_rng(0))
    p = sc.params
    theta = np.random.default_rng(1).uniform(1, 10, n) if spread else np.ones(n)
    flt = SafetyFilter(
        FilterConfig(gamma=p["gamma"], safety_radius=p["safety_radius"], u_max=p["u_max"], dt=DT)
    )
    out = []
    for _ in range(steps):
        u = move_to_goal(x, goals, p["k"], p["u_max"])
        out.append((x[None], u[None]))
        x = x + DT * flt.apply(x[None], u[None], theta[None]).actions[0]
    return flt, out, theta[None]


def best_time(run, repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    rows = []
    for n in SIZES:
        cells = []
        for spread in (False, True):
            flt, seq, theta = states(n, spread, 40)
            for x, u in seq[:3]:  # equal bit for bit (and compiled) before timing
                a = flt.apply(x, u, theta).actions
                b = flt.apply(x, u, theta, with_rows=True).actions
                if n <= sizes.COMPILED_FILTER_MAX_AGENTS and not np.array_equal(a, b):
                    raise AssertionError(f"N = {n}: the two paths disagree")

            def dense_pass(flt=flt, seq=seq, theta=theta) -> None:
                omega = flt._weights.matrix(theta, None)
                for x, u in seq:
                    dense.dense_result(
                        flt.config, x, u, omega, flt._default_bodies[(1, x.shape[1])]
                    )

            def general(flt=flt, seq=seq, theta=theta) -> None:
                for x, u in seq:
                    flt.apply(x, u, theta, with_rows=True)

            t_dense, t_general = np.inf, np.inf
            for _ in range(args.repeats):  # alternating blocks
                t_dense = min(t_dense, best_time(dense_pass, 1))
                t_general = min(t_general, best_time(general, 1))
            per = 1e6 / (len(seq) * n)
            ratio = t_dense / t_general
            cells += [f"{t_dense * per:.2f}", f"{t_general * per:.2f}", f"{ratio:.2f}"]
        rows.append(f"| {n} | " + " | ".join(cells) + " |")
        print(rows[-1], flush=True)
    text = "\n".join(
        [
            "# The compiled all-pairs filter pass against the general path",
            "",
            f"Written by `python -m benchmarks.speed.dense_filter_speed` ({machine(1)}). "
            "Microseconds per agent per filtered "
            f"step of the `crowd` scenario (40 steps, the best of {args.repeats} alternating "
            "blocks); both paths give the same actions bit for bit. The filter takes the dense "
            "pass up to `sizes.COMPILED_FILTER_MAX_AGENTS` = "
            f"{sizes.COMPILED_FILTER_MAX_AGENTS} agents an env.",
            "",
            "| N | dense, theta equal [µs] | general [µs] | dense / general "
            "| dense, theta 1..10 [µs] | general [µs] | dense / general |",
            "|---|---|---|---|---|---|---|",
            *rows,
            "",
        ]
    )
    out = RESULTS / "dense_filter_speed.md"
    out.write_text(text)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
