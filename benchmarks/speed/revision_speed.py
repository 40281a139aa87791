"""The speed of this checkout against another revision (by default the commit before the house
was rebuilt), in the same run: each case timed in a process of its own for each tree, the trees
alternating block by block, the ratio of medians reported (this checkout / the other; 1.00 is
the same speed, above is faster). Written to ``benchmarks/results/revision_speed.md``.

    python -m benchmarks.speed.revision_speed [--rev 927dbd7] [--blocks 5] [--seconds 2]

The cases are those of ``env_speed.py`` and ``scaling.py`` that the move could touch: the
filtered ``BatchedEnv`` crowd (16 agents x 256 envs, and 64 x 32), the filtered single env at
N = 6, the filtered crowd step on plain arrays at N = 1,000 and 10,000 (theta 1..10), and a
double-integrator crowd of 100. Only public paths are used, so both trees run the same code.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from benchmarks.harness import RESULTS, ROOT

OUT = RESULTS / "revision_speed.md"

# each case: agent-steps per second over ``seconds`` after a warm-up, printed as JSON
CASE = r"""
import json, sys, time
import numpy as np

case, seconds = sys.argv[1], float(sys.argv[2])

def rate(step, agents):
    for _ in range(3):
        step()
    n, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        step()
        n += 1
    return n * agents / (time.perf_counter() - start)

# the trees compared may span 1.0, which exported BatchedEnv at the top, filtered every env by
# default and removed the alias modules: each name from where its tree has it
try:
    from rsvo_env import BatchedEnv
except ImportError:
    from rsvo_env.vector import BatchedEnv
try:
    from rsvo_env.control.nominal import move_to_goal
except ImportError:
    from rsvo_env.nominal import move_to_goal

if case.startswith("batched"):
    n, e = (16, 256) if case == "batched 16x256" else (64, 32)
    env = BatchedEnv("crowd", num_envs=e, num_agents=n, safety_filter=True)
    env.reset(seed=0)
    a = np.random.default_rng(0).uniform(-1, 1, (e, n, 2))
    r = rate(lambda: env.step(a), n * e)
elif case == "single 6":
    import importlib
    import rsvo_env
    try:  # from 1.0 every env filters
        env = rsvo_env.parallel_env("crowd", num_agents=6, max_steps=10**9, safety_filter=True)
    except TypeError:  # before it, the filter a wrapper of the top-level package wrappers
        bare = rsvo_env.parallel_env("crowd", num_agents=6, max_steps=10**9)
        env = importlib.import_module("wrappers").RCBFSafetyFilter(bare)
    env.reset(seed=0)
    acts = {k: np.array([0.5, 0.2]) for k in env.possible_agents}
    r = rate(lambda: env.step(acts), 6)
elif case.startswith("arrays"):
    from rsvo_env import FilterConfig, SafetyFilter
    from rsvo_env.scenarios import Crowd
    n = int(case.split()[1])
    x, _, goals = Crowd(num_agents=n).initial_state(np.random.default_rng(0))
    theta = np.random.default_rng(1).uniform(1, 10, n)
    f = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=1.0, u_max=2.0, dt=0.05))
    state = {"x": x}
    def step():
        u = f.filter(state["x"], move_to_goal(state["x"], goals, 2.0, 2.0), theta).actions
        state["x"] = state["x"] + 0.05 * u
    r = rate(step, n)
elif case == "double 100":
    env = BatchedEnv("custom", num_envs=1, safety_filter=True, dynamics="double_integrator",
                     starts=np.c_[np.arange(100) % 10 * 3.0, np.arange(100) // 10 * 3.0],
                     goals=np.c_[27 - np.arange(100) % 10 * 3.0, 27 - np.arange(100) // 10 * 3.0],
                     dt=0.05, max_steps=10**9)
    env.reset(seed=0)
    r = rate(lambda: env.step(env.nominal_actions()), 100)
print(json.dumps(r))
"""
CASES = ["batched 16x256", "batched 64x32", "single 6", "arrays 1000", "arrays 10000", "double 100"]


def measure(tree: Path, case: str, seconds: float) -> float:
    env = dict(os.environ, PYTHONPATH=str(tree), RSVO_NUM_THREADS="1")
    out = subprocess.run(
        [sys.executable, "-c", CASE, case, str(seconds)],
        cwd=tree,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rev", default="927dbd7", help="the other revision (default: pre-move)")
    ap.add_argument("--blocks", type=int, default=5)
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--cases", nargs="+", choices=CASES, default=CASES, help="(default: all)")
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        other = Path(tmp) / "other"
        subprocess.run(
            ["git", "-C", str(ROOT), "worktree", "add", "--detach", str(other), args.rev],
            check=True,
            capture_output=True,
        )
        try:
            rates: dict[tuple[str, str], list[float]] = {}
            for block in range(args.blocks):
                trees = [("now", ROOT), ("other", other)]
                for name, tree in trees if block % 2 == 0 else trees[::-1]:
                    for case in args.cases:
                        rates.setdefault((name, case), []).append(measure(tree, case, args.seconds))
                print(f"block {block + 1}/{args.blocks}", flush=True)
        finally:
            subprocess.run(
                ["git", "-C", str(ROOT), "worktree", "remove", "--force", str(other)], check=True
            )
    head = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
    ).stdout.strip()
    lines = [
        "# Speed against another revision: this checkout against the library at --rev",
        "",
        f"`python -m benchmarks.speed.revision_speed --rev {args.rev} --blocks {args.blocks} "
        f"--seconds {args.seconds}{' --cases ...' if args.cases != CASES else ''}`: `{head}` (now) "
        f"against `{args.rev}`, each case in a process of its own per tree, the trees "
        "alternating block by block, one thread, on this project's 2-core machine (other "
        "processes share it). Agent-steps per second, medians over the blocks; ratio = now / "
        "then (1.00 the same speed).",
        "",
        "| case | now | then | ratio |",
        "|---|---|---|---|",
    ]
    for case in args.cases:
        now = statistics.median(rates[("now", case)])
        then = statistics.median(rates[("other", case)])
        lines.append(f"| {case} | {now:,.0f} | {then:,.0f} | {now / then:.3f} |")
    args.out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
