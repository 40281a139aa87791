"""R-ORCA's cost, in one process, alternating blocks: its compiled stage against ORCA's whole C++
step (pyrvo ``do_step``) per agent-step on the same dense crowds, and a ``BatchedEnv`` crowd
step with ``nominal_actions()`` against one with given actions. One thread. Writes
benchmarks/results/rorca_speed.md.

    python benchmarks/rorca_speed.py [--blocks 5] [--sizes 100 1000 10000]
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from scaling import DT, Orca  # noqa: E402

from rsvo_env.control import rorca  # noqa: E402
from rsvo_env.control.nominal import move_to_goal  # noqa: E402
from rsvo_env.envs.vector import BatchedEnv  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"


def module_at(rev: str) -> object:
    """``rsvo_env/control/rorca.py`` as it was at git revision ``rev``, imported beside today's."""
    import importlib.util
    import subprocess
    import tempfile

    root = Path(__file__).resolve().parents[1]
    src = subprocess.run(["git", "show", f"{rev}:rsvo_env/control/rorca.py"], cwd=root,
                         capture_output=True, text=True, check=True).stdout  # fmt: skip
    path = Path(tempfile.mkdtemp()) / "rorca_before.py"
    path.write_text(src)
    spec = importlib.util.spec_from_file_location("rorca_before", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def stage_against_orca(n: int, blocks: int, before: object) -> dict:
    """Microseconds per agent-step: ORCA's C++ step on its crowd, and R-ORCA's stage on the
    same positions, velocities and preferred velocities (theta U(1, 10), pad 1.05, tau 2)."""
    orca = Orca(n)
    for _ in range(20):
        orca.step()
    sc, reps = orca.sc, max(3, 20_000 // n)
    orca_s = rorca_s = before_s = 0.0
    for _ in range(blocks):
        x = orca.positions()[None]
        v = np.array([[p.x, p.y] for p in map(orca.sim.get_agent_velocity, range(n))])[None]
        pref = move_to_goal(x, orca.goals[None], sc.params["k"], sc.params["u_max"])
        theta = np.random.default_rng(1).uniform(1, 10, (1, n))
        rules = rorca.Rules(np.zeros((1, n), bool), orca.goals[None], np.zeros((1, n), bool))
        args = (x, v, pref, 1.05 * sc.radii, theta, ["asymmetric"], sc.params["u_max"], DT)
        rorca.rorca_velocities(*args, rules=rules)  # compiled, warm
        t0 = time.perf_counter()
        for _ in range(reps):
            rorca.rorca_velocities(*args, rules=rules)
        rorca_s += time.perf_counter() - t0
        before.rorca_velocities(*args, rules=rules)
        t0 = time.perf_counter()
        for _ in range(reps):
            before.rorca_velocities(*args, rules=rules)
        before_s += time.perf_counter() - t0
        orca.busy = 0.0
        for _ in range(reps):
            orca.step()
        orca_s += orca.busy
    per = 1e6 / (blocks * reps * n)
    return {"n": n, "orca": orca_s * per, "rorca": rorca_s * per, "ratio": rorca_s / orca_s,
            "before": before_s * per, "before_ratio": before_s / orca_s}  # fmt: skip


def env_steps(blocks: int, before: object, steps: int = 20) -> dict:
    """Agent-steps/s of the 16 x 256 crowd: a step with given actions, and a step with
    ``nominal_actions()`` computed first (R-ORCA, the crowd's scripted controller)."""
    env = BatchedEnv("crowd", num_envs=256, num_agents=16, safety_filter=True)
    env.reset(seed=0)
    for _ in range(30):
        env.step(env.nominal_actions())
    given = env.nominal_actions()
    t_given = t_nominal = t_before = 0.0
    today = rorca.rorca_velocities
    for _ in range(blocks):
        t0 = time.perf_counter()
        for _ in range(steps):
            env.step(given)
        t_given += time.perf_counter() - t0
        t0 = time.perf_counter()
        for _ in range(steps):
            env.step(env.nominal_actions())
        t_nominal += time.perf_counter() - t0
        rorca.rorca_velocities = before.rorca_velocities  # the scenario calls it through rorca
        try:
            t0 = time.perf_counter()
            for _ in range(steps):
                env.step(env.nominal_actions())
            t_before += time.perf_counter() - t0
        finally:
            rorca.rorca_velocities = today
    agents = blocks * steps * 256 * 16
    return {"given": agents / t_given, "nominal": agents / t_nominal, "ratio": t_given / t_nominal,
            "before": agents / t_before, "before_ratio": t_given / t_before}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--blocks", type=int, default=5)
    p.add_argument("--sizes", type=int, nargs="+", default=[100, 1000, 10_000])
    p.add_argument("--rev", default="adfb164", help="R-ORCA before its compiled stage")
    p.add_argument("--out", default=str(RESULTS / "rorca_speed.md"))
    args = p.parse_args(argv)
    before = module_at(args.rev)
    rows = [stage_against_orca(n, args.blocks, before) for n in args.sizes]
    env = env_steps(args.blocks, before)
    lines = [
        "# R-ORCA's cost",
        "",
        f"Written by `python benchmarks/rorca_speed.py --blocks {args.blocks}` on "
        f"{platform.machine()}, one thread, ORCA and R-ORCA alternating in blocks in one "
        "process on the same dense crowd (`benchmarks/scaling.py`'s, theta U(1, 10)); "
        f"'before': R-ORCA at {args.rev}, before its compiled stage, in the same blocks.",
        "",
        "| N | ORCA's C++ step [us/agent-step] | R-ORCA [us/agent-step] | R-ORCA / ORCA | "
        "before [us/agent-step] | before / ORCA |",
        "|---|---|---|---|---|---|",
        *(f"| {r['n']:,} | {r['orca']:.2f} | {r['rorca']:.2f} | {r['ratio']:.2f} | "
          f"{r['before']:.2f} | {r['before_ratio']:.2f} |" for r in rows),  # fmt: skip
        "",
        "`BatchedEnv(\"crowd\", num_envs=256, num_agents=16, safety_filter=True)`: a step with "
        f"given actions {env['given'] / 1e6:.2f} M agent-steps/s, a step with "
        f"`nominal_actions()` {env['nominal'] / 1e6:.2f} M, {env['ratio']:.2f}x of it (before: "
        f"{env['before'] / 1e6:.2f} M, {env['before_ratio']:.2f}x).",
        "",
    ]
    Path(args.out).write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
