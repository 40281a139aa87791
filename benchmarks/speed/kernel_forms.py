"""Serial or prange form, on one thread: which runs a compiled kernel faster, per problem size.

numba compiles a ``prange`` body as a function of its own and, finding no aliasing, marks its
arrays ``noalias``; the loops inside then keep their values in registers. On one thread
(``numba.set_num_threads(1)``) a launch costs about a microsecond and waits for no other
thread. This times both forms of the dense filter pass (``solvers.dense``) on ``crowd`` states
(E envs x N agents, move-to-goal, 100 steps in) and of the exact solver over rows stored by
agent (``solvers.exact.solve_csr``, the rows of one crowd of N agents), alternating, the best of
``--repeats`` blocks, both forms checked equal bit for bit.
``rsvo_env.util.sizes.PRANGE_FORM_MIN_AGENTS``
is where the prange form starts to win. Writes ``benchmarks/results/kernel_forms.md``.

    python -m benchmarks.speed.kernel_forms [--repeats 5]
"""

from __future__ import annotations

import argparse
import timeit
from collections.abc import Callable

import numba
import numpy as np

from benchmarks.harness import RESULTS, machine
from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.filter import dense
from rsvo_env.qp import exact
from rsvo_env.util import sizes

DENSE_SIZES = ((6, 1), (32, 1), (6, 8), (100, 1), (6, 32), (16, 32), (4, 256), (64, 32), (350, 1))
CSR_SIZES = (100, 1000, 10000)


def crowd(n: int, e: int) -> BatchedEnv:
    env = BatchedEnv("crowd", num_envs=e, num_agents=n, safety_filter=True, nominal="move_to_goal")
    env.reset(seed=0)
    for _ in range(100):
        env.step(env.nominal_actions())
    return env


def race(forms: dict[str, Callable[[], tuple]], repeats: int) -> dict[str, float]:
    """Microseconds a call of each form, the best of ``repeats`` alternating blocks; the forms'
    outputs must agree bit for bit."""
    outs = [f() for f in forms.values()]
    for a, b in zip(outs[0], outs[1], strict=True):
        if not np.array_equal(a, b):
            raise AssertionError("the two forms disagree")
    block = timeit.Timer(next(iter(forms.values()))).autorange()[0]
    best = dict.fromkeys(forms, np.inf)
    for _ in range(repeats):
        for name, f in forms.items():
            best[name] = min(best[name], timeit.timeit(f, number=block) / block * 1e6)
    return best


def dense_forms(n: int, e: int) -> dict[str, Callable[[], tuple]]:
    env = crowd(n, e)
    sim, s = env.sim, env.sim.state
    flt = sim.filters[0]
    bodies = next(iter(flt._default_bodies.values()))
    u = np.ascontiguousarray(sim.nominal_controls())
    args = (
        np.ascontiguousarray(s.positions),
        u,
        sim.weights.matrix,
        float(flt.config.gamma),
        bodies.radii,
        bodies.lo,
        bodies.hi,
    )

    def run(kernel) -> Callable[[], tuple]:
        def call() -> tuple:
            out = dense._outputs(e, n)
            kernel(*args, *out)
            return out

        return call

    return {"serial": run(dense._serial), "prange": run(dense._parallel)}


def csr_forms(n: int) -> dict[str, Callable[[], tuple]]:
    env = crowd(n, 1)
    sim, s = env.sim, env.sim.state
    flt = sim.filters[0]
    u = sim.nominal_controls()
    rows = flt.apply(s.positions, u, s.theta, None, sim.weights.matrix, with_rows=True).rows
    bodies = next(iter(flt._default_bodies.values()))
    nominal, lo, hi, _ = exact._batch(u.reshape(-1, 2), bodies.lo, bodies.hi)
    args = (
        nominal,
        np.ascontiguousarray(rows.flat_A),
        np.ascontiguousarray(rows.flat_b),
        np.ascontiguousarray(rows.offsets, dtype=np.int64),
        lo,
        hi,
    )

    def run(kernel) -> Callable[[], tuple]:
        def call() -> tuple:
            out = exact._batch(nominal, lo, hi)[3]
            kernel(*args, *out)
            return out

        return call

    return {"serial": run(exact._solve_csr_serial), "prange": run(exact._solve_csr_parallel)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    numba.set_num_threads(1)
    lines = []
    for n, e in DENSE_SIZES:
        t = race(dense_forms(n, e), args.repeats)
        lines.append(
            f"| dense pass | {n} x {e} | {n * e} | {t['serial']:.1f} | {t['prange']:.1f} "
            f"| {t['prange'] / t['serial']:.2f} |"
        )
        print(lines[-1], flush=True)
    for n in CSR_SIZES:
        t = race(csr_forms(n), args.repeats)
        lines.append(
            f"| CSR solve | {n} x 1 | {n} | {t['serial']:.1f} | {t['prange']:.1f} "
            f"| {t['prange'] / t['serial']:.2f} |"
        )
        print(lines[-1], flush=True)
    text = "\n".join(
        [
            "# Serial or prange form, on one thread",
            "",
            f"Written by `python -m benchmarks.speed.kernel_forms` ({machine(1, 'numba')}). "
            "Microseconds a "
            f"call, the best of {args.repeats} alternating blocks; both forms give the same "
            "outputs bit for bit. The library calls the prange form from "
            f"`sizes.PRANGE_FORM_MIN_AGENTS` = {sizes.PRANGE_FORM_MIN_AGENTS} agents a call "
            "(`rsvo_env/util/threads.py`).",
            "",
            "| kernel | N x E | agents a call | serial [µs] | prange, one thread [µs] "
            "| prange / serial |",
            "|---|---|---|---|---|---|",
            *lines,
            "",
        ]
    )
    out = RESULTS / "kernel_forms.md"
    out.write_text(text)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
