"""Gymnasium's vector entry point against its sync mode: ``gymnasium.make_vec(id, 64,
vectorization_mode="vector_entry_point")`` (the batched core, ``rsvo_env.wrappers.JointVectorEnv``)
against ``vectorization_mode="sync"`` (64 ``gymnasium.make(id)`` envs stepped one by one), for
every registered id, the filter on, random joint actions. One process, alternating blocks of
steps, the ratio of the env-steps per second. Writes benchmarks/results/gym_vector_speed.md.

    python -m benchmarks.speed.gym_vector_speed [--envs 64] [--blocks 5] [--steps 20]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import gymnasium
import numpy as np

import rsvo_env  # noqa: F401  (registers the ids)
from benchmarks.harness import RESULTS, machine
from rsvo_env.envs.registration import IDS


def rates(env_id: str, envs: int, blocks: int, steps: int) -> dict:
    """Env-steps per second of both modes on the same seeds and actions, alternating blocks."""
    modes = {
        m: gymnasium.make_vec(env_id, envs, vectorization_mode=m)
        for m in ("vector_entry_point", "sync")
    }
    rng = np.random.default_rng(0)
    seconds = dict.fromkeys(modes, 0.0)
    for env in modes.values():
        env.reset(seed=0)
        env.step(env.action_space.sample())  # warm
    for _ in range(blocks):
        actions = rng.uniform(-1, 1, (steps, *modes["sync"].action_space.shape))
        for mode, env in modes.items():
            t0 = time.perf_counter()
            for a in actions:
                env.step(a.astype(np.float32))
            seconds[mode] += time.perf_counter() - t0
    for env in modes.values():
        env.close()
    done = blocks * steps * envs
    return {
        "id": env_id,
        "vector": done / seconds["vector_entry_point"],
        "sync": done / seconds["sync"],
        "ratio": seconds["sync"] / seconds["vector_entry_point"],
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--envs", type=int, default=64)
    ap.add_argument("--blocks", type=int, default=5)
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--out", type=Path, default=RESULTS / "gym_vector_speed.md")
    args = ap.parse_args(argv)
    rows = [rates(env_id, args.envs, args.blocks, args.steps) for env_id in IDS]
    lines = [
        "# Gymnasium's vector entry point",
        "",
        f"Written by `python -m benchmarks.speed.gym_vector_speed --envs {args.envs} --blocks "
        f"{args.blocks} --steps {args.steps}` on {machine()}: "
        f"`gymnasium.make_vec(id, {args.envs}, vectorization_mode=...)`, the filter on, random "
        "joint actions, the two modes alternating in blocks of steps in one process.",
        "",
        '| id | `"vector_entry_point"` [env-steps/s] | `"sync"` [env-steps/s] | ratio |',
        "|---|---|---|---|",
        *(
            f"| `{r['id']}` | {r['vector']:,.0f} | {r['sync']:,.0f} | {r['ratio']:.1f}x |"
            for r in rows
        ),
        "",
    ]
    args.out.write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
