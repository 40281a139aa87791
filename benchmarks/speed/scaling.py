"""How the filter scales with the crowd, in one process, against ORCA's C++ (pyrvo).

1. Single-integrator ``crowd`` at N in {10, 100, 1,000, 10,000, 30,000}: the filtered step on
   plain arrays (``SafetyFilter.filter``: neighbours, rows, solve; then x += dt u), in
   microseconds per agent-step, with theta equal and spread over 1..10; and ORCA (pyrvo, the
   ``baselines`` extra) on the same starts, goals, radius (R/2 each) and speed limit, its C++
   ``do_step`` alone timed. Blocks of steps alternate between the two; each figure is the fastest
   block (the least disturbed by other processes on a shared machine). Our smallest distance
   over every step is checked against R.
2. Double-integrator crowds at N in {100, 1,000}: the filtered step (acceleration box; the
   stopping-segment, backup and braking barriers, no user radius) plus the exact zero-order-hold
   step, per agent-step and against the single integrator's cost at the same N; the share of
   infeasible agent-steps; every 20th step, actions and flags against the all-pairs filter's.
3. A 10,000-agent crowd for 1,000 filtered steps through ``BatchedEnv`` (scripted nominal), and
   on plain arrays, each in a fresh process: wall time, collisions, peak memory per agent.

Writes ``benchmarks/results/scaling.md`` and ``scaling.png``.

    python -m benchmarks.speed.scaling [--quick]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from benchmarks.harness import RESULTS
from benchmarks.reports import scaling_report as report  # noqa: E402
from rsvo_env.control.nominal import move_to_goal
from rsvo_env.dynamics import MODELS, double_integrator_step
from rsvo_env.dynamics.unicycle import unicycle_step
from rsvo_env.filter.safety import FilterConfig, SafetyFilter
from rsvo_env.geometry import pairs
from rsvo_env.geometry.bodies import Bodies
from rsvo_env.qp import exact
from rsvo_env.scenarios import Crowd
from rsvo_env.util import sizes
from rsvo_env.util.neighbors import nearest_distance

DT = 0.05
SIZES = (10, 100, 1000, 10_000, 30_000)


def crowd_start(n: int, seed: int = 0) -> tuple[Crowd, np.ndarray, np.ndarray]:
    sc = Crowd(num_agents=n)
    start, _, goals = sc.initial_state(np.random.default_rng(seed))
    return sc, start, goals


def scores(n: int, spread: bool) -> np.ndarray:
    return np.random.default_rng(1).uniform(1, 10, n) if spread else np.ones(n)


class Ours:
    """The filter on plain arrays plus the Euler step."""

    def __init__(self, n: int, spread: bool) -> None:
        self.sc, self.x, self.goals = crowd_start(n)
        p = self.sc.params
        self.theta = scores(n, spread)
        self.k, self.u_max, self.R = p["k"], p["u_max"], p["safety_radius"]
        self.flt = SafetyFilter(
            FilterConfig(gamma=p["gamma"], safety_radius=self.R, u_max=self.u_max, dt=DT)
        )
        self.min_distance = float(nearest_distance(self.x).min())

    def step(self) -> None:
        u = move_to_goal(self.x, self.goals, self.k, self.u_max)
        self.x = self.x + DT * self.flt.filter(self.x, u, self.theta).actions

    def check(self) -> None:
        self.min_distance = min(self.min_distance, float(nearest_distance(self.x).min()))


class Orca:
    """ORCA (pyrvo) on the same crowd; ``busy`` adds up the time of its C++ step alone."""

    def __init__(self, n: int) -> None:
        import pyrvo

        self.sc, x, self.goals = crowd_start(n)
        p = self.sc.params
        self.k, self.u_max = p["k"], p["u_max"]
        self.sim = pyrvo.RVOSimulator()
        self.sim.set_time_step(DT)
        # neighbour distance, max neighbours, time horizons (agents, obstacles), radius, speed
        R = p["safety_radius"]
        self.sim.set_agent_defaults(5.0 * R, 10, 2.0, 2.0, R / 2, self.u_max)
        for xi in x:
            self.sim.add_agent((float(xi[0]), float(xi[1])))
        self.n = n
        self.busy = 0.0

    def positions(self) -> np.ndarray:
        return np.array([(p.x, p.y) for p in map(self.sim.get_agent_position, range(self.n))])

    def step(self) -> None:
        u = move_to_goal(self.positions(), self.goals, self.k, self.u_max)
        for i in range(self.n):
            self.sim.set_agent_pref_velocity(i, (float(u[i, 0]), float(u[i, 1])))
        t0 = time.perf_counter()
        self.sim.do_step()
        self.busy += time.perf_counter() - t0


class DoubleIntegrator:
    """A double-integrator crowd: the filter on plain arrays plus the exact ZOH step. The
    nominal steers the velocity to the move-to-goal command: a = k_v (v_des - v), in the box."""

    GAMMA, A_MAX, K_V = 2.0, 1.0, 2.0

    def __init__(self, n: int, spread: bool, barrier: str = "segment") -> None:
        self.sc, self.p, self.goals = crowd_start(n)
        par = self.sc.params
        self.v = np.zeros_like(self.p)
        self.theta = scores(n, spread)
        self.k, self.v_max, self.R = par["k"], par["u_max"], par["safety_radius"]
        self.flt = SafetyFilter(
            FilterConfig(
                gamma=self.GAMMA,
                safety_radius=self.R,
                u_max=self.A_MAX,
                dt=DT,
                dynamics="double_integrator",
                barrier=barrier,
            )
        )
        self.agent_steps = self.infeasible = self.mismatches = self.checks = 0
        self.min_distance = float(nearest_distance(self.p).min())

    def nominal(self) -> np.ndarray:
        v_des = move_to_goal(self.p, self.goals, self.k, self.v_max)
        return np.clip(self.K_V * (v_des - self.v), -self.A_MAX, self.A_MAX)

    def step(self) -> None:
        nominal = self.nominal()
        res = self.flt.filter(self.p, nominal, self.theta, velocities=self.v)
        self.last = (self.p, self.v, nominal, res)
        self.p, self.v = double_integrator_step(self.p, self.v, res.actions, DT)

    def check(self, all_pairs: bool) -> None:
        """Count infeasible agent-steps; optionally redo the step with every pair."""
        res = self.last[3]
        self.agent_steps += res.feasible.size
        self.infeasible += int((~res.feasible).sum())
        self.min_distance = min(self.min_distance, float(nearest_distance(self.p).min()))
        if all_pairs:
            self.checks += 1
            self.mismatches += int(not self.matches_all_pairs())

    def matches_all_pairs(self) -> bool:
        """The step's actions and flags are those of the filter over every pair."""
        p, v, nominal, res = self.last
        cfg = self.flt.config
        I, J = pairs.all_pairs(len(p))
        w = self.flt.pair_weights(self.theta, None, I, J)
        bodies = Bodies.of(cfg, 1, len(p))
        rows, _ = cfg.model.filter_rows(cfg, p, v, w, I, J, bodies, None, len(p))
        u, feasible = exact.solve_csr(nominal, rows.flat_A, rows.flat_b, rows.offsets, cfg.lo,
                                      cfg.hi)[:2]  # fmt: skip
        same_flags = np.array_equal(feasible, res.feasible)
        return bool(same_flags and np.abs(u - res.actions).max() <= 1e-12 * self.A_MAX)


class Unicycle:
    """A unicycle crowd: the filter on plain arrays (look-ahead points, ``docs/unicycle.md``)
    plus the exact step of the look-ahead hold. The crowd's starts and goals spread by
    ``(R + 4 l) / R`` so the look-ahead points start apart; nominal: full speed toward the
    goal, turning at ``K_W`` times the heading error."""

    LOOKAHEAD, W_MAX = (MODELS["unicycle"].scenario_defaults[k] for k in ("lookahead", "w_max"))
    K_W = 2.0

    def __init__(self, n: int, spread: bool, gamma: float | None = None) -> None:
        self.sc, p, goals = crowd_start(n)
        par = self.sc.params
        self.gamma = par["gamma"] if gamma is None else gamma
        self.R, self.v_max = par["safety_radius"], par["u_max"]
        grow = (self.R + 4.0 * self.LOOKAHEAD) / self.R
        centre = p.mean(axis=0)
        self.p, self.goals = centre + grow * (p - centre), centre + grow * (goals - centre)
        d = self.goals - self.p
        self.th = np.arctan2(d[:, 1], d[:, 0])
        self.theta = scores(n, spread)
        self.flt = SafetyFilter(
            FilterConfig(gamma=self.gamma, safety_radius=self.R, u_max=self.v_max, dt=DT,
                         dynamics="unicycle", lookahead=self.LOOKAHEAD, w_max=self.W_MAX)
        )  # fmt: skip
        self.agent_steps = self.infeasible = self.mismatches = self.checks = 0
        self.min_distance = float(nearest_distance(self.p).min())

    def nominal(self) -> np.ndarray:
        d = self.goals - self.p
        err = np.angle(np.exp(1j * (np.arctan2(d[:, 1], d[:, 0]) - self.th)))
        v = np.minimum(np.linalg.norm(d, axis=1), self.v_max) * np.maximum(np.cos(err), 0.0)
        return np.c_[v, np.clip(self.K_W * err, -self.W_MAX, self.W_MAX)]

    def step(self) -> None:
        res = self.flt.filter(self.p, self.nominal(), self.theta, headings=self.th)
        self.last = res
        self.p, self.th = unicycle_step(self.p, self.th, res.actions, self.LOOKAHEAD, DT)

    def check(self, all_pairs: bool) -> None:
        """Count infeasible agent-steps (the all-pairs comparison is the double integrator's)."""
        self.agent_steps += self.last.feasible.size
        self.infeasible += int((~self.last.feasible).sum())
        self.min_distance = min(self.min_distance, float(nearest_distance(self.p).min()))


UNICYCLE_GAMMAS = (
    ("unicycle, gamma 10 (the single integrator's)", None),
    ("unicycle, gamma 2 (the double integrator's)", DoubleIntegrator.GAMMA),
)


def timed(sim, steps: int, after=None) -> float:
    """Seconds of ``steps`` steps (ORCA: its C++ step alone); ``after`` runs untimed."""
    busy = 0.0
    for _ in range(steps):
        if isinstance(sim, Orca):
            before = sim.busy
            sim.step()
            busy += sim.busy - before
        else:
            t0 = time.perf_counter()
            sim.step()
            busy += time.perf_counter() - t0
        if after is not None:
            after()
    return busy


def alternate(sims: dict, n: int, steps: int, blocks: int, after: dict) -> dict[str, float]:
    """Microseconds per agent-step of each sim in its fastest of ``blocks`` alternating blocks
    (other processes only ever slow a block down)."""
    for name, sim in sims.items():
        timed(sim, 1, after.get(name))  # warm: numba compiles, caches fill
    per = {name: [] for name in sims}
    for _ in range(blocks):
        for name, sim in sims.items():
            per[name].append(1e6 * timed(sim, steps, after.get(name)) / (steps * n))
    return {name: float(np.min(v)) for name, v in per.items()}


def rss() -> int:
    """This process's resident memory now, in bytes (Linux)."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def big_crowd(mode: str, n: int, steps: int) -> dict:
    """A crowd of n agents for ``steps`` filtered steps in this (fresh) process: wall time,
    the smallest distance over every step, and the peak resident memory beyond what the
    imports hold (sampled after the setup and after every step)."""
    # compile first (numba's own memory is not the crowd's), on a crowd beyond the compiled
    # all-pairs pass, so that the kernels of the general path are the ones compiled
    Ours(2 * sizes.COMPILED_FILTER_MAX_AGENTS, spread=False).step()
    base = peak = rss()
    t0 = time.perf_counter()
    if mode == "env":
        from rsvo_env.envs.vector import BatchedEnv

        # the move-to-goal of section 1
        kwargs = {"num_agents": n, "max_cycles": steps + 1, "nominal": "move_to_goal"}
        venv = BatchedEnv("crowd", num_envs=1, **kwargs)
        venv.reset(seed=0)
        setup, peak = time.perf_counter() - t0, max(peak, rss())
        smallest, t1 = np.inf, time.perf_counter()
        for _ in range(steps):
            info = venv.step(venv.nominal_actions())[4]
            smallest = min(smallest, float(info["min_distance"].min()))
            peak = max(peak, rss())
    else:
        sim = Ours(n, spread=False)
        setup, peak = time.perf_counter() - t0, max(peak, rss())
        t1 = time.perf_counter()
        for _ in range(steps):
            sim.step()
            sim.check()
            peak = max(peak, rss())
        smallest = sim.min_distance
    return {
        "mode": mode,
        "n": n,
        "steps": steps,
        "setup_s": setup,
        "wall_s": time.perf_counter() - t1,
        "min_distance": smallest,
        "peak_bytes": peak - base,
    }


def fresh(mode: str, n: int, steps: int) -> dict:
    out = subprocess.run(
        [sys.executable, __file__, "--big", mode, str(n), str(steps)],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    return json.loads(out.strip().splitlines()[-1])


def double_integrator_rows(blocks: int) -> list[dict]:
    """Section 2: each barrier's double-integrator crowd against the single integrator."""
    di = []
    for n in (100, 1000):
        for barrier in ("segment", "backup", "braking"):
            steps = 40 if n <= 100 else 10
            sim = DoubleIntegrator(n, spread=True, barrier=barrier)
            si = Ours(n, spread=True)
            k = [0]

            def after(sim=sim, k=k):
                k[0] += 1
                sim.check(all_pairs=k[0] % 20 == 0)

            t = alternate({"di": sim, "si": si}, n, steps, blocks, {"di": after})
            di.append(
                {
                    "n": n,
                    "barrier": barrier,
                    "di": t["di"],
                    "si": t["si"],
                    "agent_steps": sim.agent_steps,
                    "infeasible": sim.infeasible,
                    "checks": sim.checks,
                    "mismatches": sim.mismatches,
                    "min_distance": sim.min_distance,
                }
            )
            print(di[-1], flush=True)
        for label, gamma in UNICYCLE_GAMMAS:  # a smaller gamma widens every culling radius
            uni, si = Unicycle(n, spread=True, gamma=gamma), Ours(n, spread=True)
            t = alternate({"di": uni, "si": si}, n, 40 if n <= 100 else 10, blocks,
                          {"di": lambda uni=uni: uni.check(False)})  # fmt: skip
            di.append({"n": n, "barrier": label, "di": t["di"], "si": t["si"],
                       "agent_steps": uni.agent_steps, "infeasible": uni.infeasible,
                       "checks": 0, "mismatches": 0, "min_distance": uni.min_distance})  # fmt: skip
            print(di[-1], flush=True)
    return di


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="N up to 1,000, fewer blocks")
    ap.add_argument("--blocks", type=int, default=7)
    ap.add_argument("--out", type=Path, default=RESULTS / "scaling.md")
    ap.add_argument("--di-only", action="store_true",
                    help="rerun section 2 alone and replace it in --out")  # fmt: skip
    ap.add_argument("--big", nargs=3, metavar=("MODE", "N", "STEPS"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.big:
        print(json.dumps(big_crowd(args.big[0], int(args.big[1]), int(args.big[2]))))
        return 0
    try:
        import pyrvo  # noqa: F401

        orca = True
    except ImportError:
        orca = False
    sizes = [n for n in SIZES if not args.quick or n <= 1000] if not args.di_only else []
    rows = []
    for n in sizes:
        steps = 20  # the same stretch of the episode at every N
        row = {"n": n, "steps": steps}
        for spread in (False, True):
            ours = Ours(n, spread)
            sims = {"ours": ours}
            if orca:
                sims["orca"] = Orca(n)
            t = alternate(sims, n, steps, args.blocks, {"ours": ours.check})
            key = "ours_spread" if spread else "ours_equal"
            row[key] = t["ours"]
            row[key + "_min_distance"] = ours.min_distance
            if orca:
                row["orca_spread" if spread else "orca"] = t["orca"]
        rows.append(row)
        print(row, flush=True)
    di = double_integrator_rows(args.blocks)
    if args.di_only:
        report.splice_di(args.out, di, DT, DoubleIntegrator)
        return 0
    big = [] if args.quick else [fresh("env", 10_000, 1000), fresh("arrays", 10_000, 1000)]
    report.write(args.out, rows, di, big, orca, args.blocks, DT, DoubleIntegrator)
    report.plot(rows, di, args.out.with_suffix(".png"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
