"""Env step cost: the batched env against VMAS, the single env against numpy.

1. ``BatchedEnv("crowd")`` with the filter, scripted nominal actions, at (N, E) in {(4, 256),
   (16, 32), (16, 256), (64, 32)}: agent-steps per second and the smallest distance seen; and
   VMAS's ``navigation`` scenario on the CPU (no safety filter; random actions) at the same sizes,
   when the ``baselines`` extra is installed.
2. The single ``RSVOParallelEnv`` (PettingZoo dicts) of ``crowd`` at N = 6, 100, 1000, bare and
   filtered, scripted nominal actions, against a reference run on the same states: the bare
   numpy work every step must do at least (x += dt u and one dense nearest-neighbour query;
   ``single_env_speed.py``, run in a process of its own so that VMAS's torch threads are not
   beside it; the ratio is within that process).
3. The same single-env ratio at N = 6 of the library as of each ``--baseline`` (by default the
   last commit before the batch-first core, and the commit at which the speed issue was filed),
   timed in its own process against the same reference.

Each figure is the best of ``--repeats`` alternating bursts (this machine's speed drifts).
Writes ``benchmarks/results/env_speed.md``.

    python -m benchmarks.speed.env_speed [--seconds 1] [--repeats 5] [--baseline REV ...|none]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from benchmarks.harness import RESULTS, ROOT, best_rates, machine
from rsvo_env.envs.vector import BatchedEnv

BATCH_SIZES = ((4, 256), (16, 32), (16, 256), (64, 32))
# the last commit before the batch-first core: "today" for the single env's speed-up
# revisions the single env at N = 6 is compared with, and what each was
BASELINES = {"a2df9b8": "before the batch-first core", "dc09414": "when issue 25 was filed"}


def batched(n: int, e: int, seen: dict) -> tuple[Callable, int]:
    # the same scripted work as the tables before R-ORCA became the default (its own cost:
    # docs/liveness.md)
    venv = BatchedEnv("crowd", num_envs=e, num_agents=n, nominal="move_to_goal")
    venv.reset(seed=0)
    key = (n, e)
    seen[key] = np.inf

    def step() -> None:
        info = venv.step(venv.nominal_actions())[4]
        seen[key] = min(seen[key], float(info["min_distance"].min()))

    return step, n * e


def vmas_navigation(n: int, e: int) -> tuple[Callable, int]:
    import torch
    import vmas

    # VMAS spawns 2N entities (agents and goals) at least 0.25 apart in [-s, s]^2 (s = 1 by
    # default); grow s with sqrt(N) from its 16-agent default so that 64 agents fit too.
    s = max(1.0, float(np.sqrt(n / 16)))
    env = vmas.make_env(
        "navigation",
        num_envs=e,
        device="cpu",
        n_agents=n,
        seed=0,
        world_spawning_x=s,
        world_spawning_y=s,
    )
    env.reset()
    gen = torch.Generator().manual_seed(0)

    def step() -> None:
        actions = [torch.rand((e, 2), generator=gen) * 2 - 1 for _ in range(n)]
        env.step(actions)

    return step, n * e


def process_rates(tree: Path, n: int, seconds: float, repeats: int) -> dict[str, float]:
    """:func:`single_env_speed.rates` at n agents in a fresh process with the library of
    ``tree`` first on its path; the reference is this checkout's code either way."""
    script = Path(__file__).with_name("single_env_speed.py")
    out = subprocess.run(
        [
            sys.executable,
            str(script),
            "--agents",
            str(n),
            "--seconds",
            str(seconds),
            "--repeats",
            str(repeats),
        ],
        cwd=tree.parent,
        env={**os.environ, "PYTHONPATH": str(tree)},
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def baseline_rates(rev: str, seconds: float, repeats: int) -> dict[str, float]:
    """:func:`process_rates` at N = 6 of the library as of git revision ``rev`` (a detached
    worktree)."""
    with tempfile.TemporaryDirectory() as tmp:
        tree = Path(tmp) / "tree"
        subprocess.run(
            ["git", "-C", str(ROOT), "worktree", "add", "--detach", str(tree), rev],
            check=True,
            capture_output=True,
        )
        try:
            return process_rates(tree, 6, seconds, repeats)
        finally:
            subprocess.run(
                ["git", "-C", str(ROOT), "worktree", "remove", "--force", str(tree)], check=True
            )


def baseline_section(rev: str, now: dict[str, float], seconds: float, repeats: int) -> list[str]:
    """The single env at N = 6, then (``rev``) and now, each against the reference timed in its
    own process."""
    then = baseline_rates(rev, seconds, repeats)
    what = BASELINES.get(rev, "an earlier library")
    lines = [
        "",
        f"## Single env at N = 6: {what} (commit `{rev}`) and now",
        "",
        f"The library as of `{rev}` (a detached worktree, in its own process) and this checkout,"
        " each timed against the same frozen reference in its own process; the multiple is of"
        " the ratios, so the machine's drift between the two processes cancels.",
        "",
        "| variant | then: env / reference | now: env / reference | now / then |",
        "|---|---|---|---|",
    ]
    for name, label in (("bare", "bare env"), ("filtered", "filtered (RCBFSafetyFilter)")):
        a, b = then[name] / then["reference"], now[name] / now["reference"]
        lines.append(f"| {label} | {a:.3f} | {b:.3f} | {b / a:.2f}x |")
        print(lines[-1], flush=True)
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seconds", type=float, default=1.0, help="length of one burst")
    ap.add_argument("--repeats", type=int, default=5, help="bursts per benchmark")
    ap.add_argument(
        "--baseline",
        nargs="+",
        default=list(BASELINES),
        help="git revisions whose single env is timed against the same reference ('none': skip)",
    )
    ap.add_argument("--out", type=Path, default=RESULTS / "env_speed.md")
    args = ap.parse_args(argv)
    try:
        import torch
        import vmas

        torch.set_num_threads(os.cpu_count() or 1)
        vmas_note = (
            f"VMAS {vmas.__version__}, torch {torch.__version__}, {torch.get_num_threads()} threads"
        )
    except ImportError:
        vmas = None
        vmas_note = "VMAS not installed (`pip install -e .[baselines]`)"
    lines = [
        "# Env step cost",
        "",
        f"Written by `python -m benchmarks.speed.env_speed` ({machine()}; "
        f"{vmas_note}). Each figure is the best of {args.repeats} alternating bursts of "
        f"{args.seconds:g} s.",
        "",
        "## Batched env (`crowd`, filter on, scripted nominal) against VMAS `navigation` (CPU)",
        "",
        "VMAS's navigation scenario has no safety filter; it steps random actions (spawn area"
        " grown with sqrt(N) beyond 16 agents, so that 64 fit). Min distance: the smallest"
        " distance between two of our agents over the whole run (R = 1).",
        "",
        "| N | E | BatchedEnv agent-steps/s | min distance seen [m] | VMAS agent-steps/s |"
        " BatchedEnv / VMAS |",
        "|---|---|---|---|---|---|",
    ]
    for n, e in BATCH_SIZES:
        seen: dict = {}
        makers = {"ours": lambda n=n, e=e, seen=seen: batched(n, e, seen)}
        if vmas is not None:
            makers["vmas"] = lambda n=n, e=e: vmas_navigation(n, e)
        r = best_rates(makers, args.seconds, args.repeats)
        v = r.get("vmas")
        lines.append(
            f"| {n} | {e} | {r['ours']:,.0f} | {seen[(n, e)]:.12f} | "
            + (f"{v:,.0f} | {r['ours'] / v:.1f}x |" if v else "— | — |")
        )
        print(lines[-1], flush=True)
    lines += [
        "",
        "## Single env (`RSVOParallelEnv`, PettingZoo dicts) against its numpy reference",
        "",
        "Reference: x += dt u plus one dense nearest-neighbour query (a KD-tree above 64 agents)"
        " on the same agents, timed in the same process as the env (one process per N, apart"
        " from the batched runs above). Scripted nominal actions computed every step, episodes"
        " reset as they end.",
        "",
        "| N | variant | agent-steps/s | µs per env step | reference agent-steps/s |"
        " env / reference |",
        "|---|---|---|---|---|---|",
    ]
    now: dict[int, dict[str, float]] = {}
    for n in (6, 100, 1000):
        # a process of its own, as the baseline's: no VMAS or torch threads beside it
        r = now[n] = process_rates(ROOT, n, args.seconds, args.repeats)
        for name, label in (("bare", "bare env"), ("filtered", "filtered (RCBFSafetyFilter)")):
            lines.append(
                f"| {n} | {label} | {r[name]:,.0f} | {n / r[name] * 1e6:,.0f} | "
                f"{r['reference']:,.0f} | {r[name] / r['reference']:.3f} |"
            )
            print(lines[-1], flush=True)
    for rev in () if args.baseline == ["none"] else args.baseline:
        lines += baseline_section(rev, now[6], args.seconds, args.repeats)
    lines.append("")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(lines))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
