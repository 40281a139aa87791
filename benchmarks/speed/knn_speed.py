"""The k-nearest-neighbour kernels of ``rsvo_env.util.neighbors``, each timed on the same batches.

Every (envs E, agents N, k) cell times insertion, ranking and env lanes on the same positions,
one thread, alternating bursts, the best of ``--repeats``; and names the kernel that
``_knn_dense`` picks there by its thresholds, with its time against the fastest one. Writes
``benchmarks/results/knn_speed.md``.

The positions are those an env steps through: random at first, then each call a small move
(0.1, the crowd's u_max dt, at a spacing of about 2), so that the order of neighbours changes
little from one call to the next. Fresh random positions every call (the table before) made
insertion's branches mispredict far more than they do in an env, and picked env lanes where
insertion is faster in the env's own step (``BatchedEnv`` 16 x 32: 2.6 M against 3.6 M
agent-steps/s).

    python -m benchmarks.speed.knn_speed [--repeats 5]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from benchmarks.harness import RESULTS, machine
from rsvo_env.util import neighbors

KERNELS = {
    "insertion": neighbors._knn_inserted,
    "ranking": neighbors._knn_ranked,
    "env lanes": neighbors._knn_lanes,
}
CELLS = [(e, n, k) for e in (1, 8, 16, 32, 64, 256) for n in (4, 8, 16, 32, 64) for k in (3, 6)]


def picked(e: int, n: int, k: int) -> str:
    """The kernel ``_knn_dense`` runs for this batch (its thresholds, read back)."""
    return ("insertion", "ranking", "env lanes")[neighbors.kernel_for(e, n)]


def time_cell(e: int, n: int, k: int, repeats: int) -> dict[str, float]:
    rng = np.random.default_rng(e * 1000 + n * 10 + k)
    calls = max(4, 8000 // (e * n))
    start = rng.uniform(0.0, 2.0 * np.sqrt(n), (1, e, n, 2))
    moves = rng.normal(0.0, 0.1 / np.sqrt(2.0), (calls, e, n, 2))
    moves[0] = 0.0
    batches = start + np.cumsum(moves, axis=0)
    dist, idx = np.empty((e, n, k)), np.empty((e, n, k), dtype=np.int64)
    best = dict.fromkeys(KERNELS, np.inf)
    for _ in range(repeats):
        for name, kernel in KERNELS.items():
            start = time.perf_counter()
            for c in range(calls):
                kernel(batches[c], k, dist, idx)
            best[name] = min(best[name], (time.perf_counter() - start) / calls)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    for kernel in KERNELS.values():  # compile outside the timing
        kernel(
            np.zeros((1, 4, 2)) + np.arange(4)[:, None],
            2,
            np.empty((1, 4, 2)),
            np.empty((1, 4, 2), dtype=np.int64),
        )
    rows, worst = [], 1.0
    for e, n, k in CELLS:
        if k >= n:
            continue
        t = time_cell(e, n, k, args.repeats)
        fastest = min(t, key=t.get)
        choice = picked(e, n, k)
        worst = max(worst, t[choice] / t[fastest])
        per = {name: f"{t[name] / (e * n) * 1e9:,.0f}" for name in KERNELS}
        rows.append(
            f"| {e} | {n} | {k} | {per['insertion']} | {per['ranking']} | {per['env lanes']} "
            f"| {choice} | {t[choice] / t[fastest]:.2f} |"
        )
        print(rows[-1], flush=True)
    text = "\n".join(
        [
            "# k-nearest-neighbour kernels",
            "",
            f"Written by `python -m benchmarks.speed.knn_speed` ({machine(1)}). "
            "Nanoseconds per agent per query, the best of "
            f"{args.repeats} alternating bursts; positions drifting as in a stepping env (each "
            "call moves every agent by about 0.1 at a spacing of about 2). All three "
            "kernels return the same neighbours bit for bit (`tests/math/test_neighbors.py`).",
            "",
            "| E | N | k | insertion [ns] | ranking [ns] | env lanes [ns] | picked "
            "| picked / fastest |",
            "|---|---|---|---|---|---|---|---|",
            *rows,
            "",
            f"The picked kernel is at most {worst:.2f}x the fastest of the three in every cell.",
            "",
        ]
    )
    out = RESULTS / "knn_speed.md"
    out.write_text(text)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
