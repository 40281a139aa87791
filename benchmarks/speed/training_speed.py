"""Training throughput, in one process: PPO through the batched env against the single-env path.

Both runs train the circular_swap residual config (6 agents, filter on, dt 0.1) with PPO, the
same hyperparameters (``training/configs/circular_swap.yaml``) and the same rollout size (the
config's ``n_steps`` x ``num_envs`` x 6 agent-steps an update):

* batched: ``SB3VecEnv(BatchedEnv(num_envs))``, one slot per agent, the config's ``n_steps``;
* single: ``SB3VecEnv`` over one filtered ``RSVOParallelEnv`` with ``ResidualAction`` (PettingZoo
  dicts, 6 slots), ``n_steps`` times ``num_envs``.

Then the crowd config with R-ORCA under the residual against move-to-goal under it. For each:
agent-steps per second with the PPO updates included, and the share of wall time in
the env step (filter included), in the filter stage alone, in the policy's forward passes
during rollouts (the rest of the rollout) and in the PPO update. One torch thread. Each figure is
the best of ``--repeats`` alternating runs. Writes ``benchmarks/results/training_speed.md``.

    python -m benchmarks.speed.training_speed [--updates 4] [--repeats 3]
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

import torch
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import VecMonitor

from benchmarks.harness import RESULTS, machine
from rsvo_env.filter.safety import SafetyFilter
from rsvo_env.training import config as configs
from rsvo_env.wrappers.sb3 import SB3VecEnv


def rollout_size(cfg: dict[str, Any]) -> int:
    """Agent-steps an update: the config's n_steps for every slot of its batched envs."""
    return cfg["ppo"]["n_steps"] * cfg["num_envs"] * cfg["env"]["num_agents"]


class Timer:
    """Accumulated seconds of the wrapped callables."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}

    def wrap(self, name: str, fn: Any) -> Any:
        self.seconds.setdefault(name, 0.0)

        def timed(*args: Any, **kwargs: Any) -> Any:
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                self.seconds[name] += time.perf_counter() - t0

        return timed


def hyper_note(cfg: dict[str, Any]) -> str:
    """The PPO settings that set the update's cost, in words."""
    ppo = cfg["ppo"]
    kwargs = ppo.get("policy_kwargs") or {}
    arch = "x".join(str(w) for w in kwargs.get("net_arch", [64, 64]))
    act = kwargs.get("activation_fn", "tanh")
    return f"{arch} {act} layers, {ppo['n_epochs']} epochs, minibatches of {ppo['batch_size']}"


def run(
    path: str, updates: int, scenario: str = "circular_swap", nominal: str | None = None
) -> dict[str, float]:
    """One PPO run of ``updates`` updates on ``path`` ("batched" or "single"), the config of
    ``scenario`` with ``env.nominal`` set to ``nominal`` where given: rates and time shares."""
    cfg = configs.load(scenario)
    if nominal is not None:
        configs.set_value(cfg, f"env.nominal={nominal}")
    cfg = configs.resolve(cfg)
    rollout = rollout_size(cfg)
    if path == "batched":
        venv = SB3VecEnv(configs.make_env(cfg, num_envs=cfg["num_envs"]))
    else:
        venv = SB3VecEnv(configs.make_parallel(cfg))
    n_steps = rollout // venv.num_envs
    hyper = {**configs.hyperparameters(cfg), "n_steps": n_steps}
    model = PPO("MlpPolicy", VecMonitor(venv), seed=0, verbose=0, **hyper)
    timer = Timer()
    venv.step_wait = timer.wrap("env", venv.step_wait)
    model.train = timer.wrap("update", model.train)
    original = SafetyFilter.apply
    SafetyFilter.apply = timer.wrap("filter", original)
    try:
        model.learn(n_steps * venv.num_envs)  # first update: compiles, warms caches
        timer.seconds = dict.fromkeys(timer.seconds, 0.0)
        t0 = time.perf_counter()
        model.learn(updates * rollout, reset_num_timesteps=False)
        total = time.perf_counter() - t0
    finally:
        SafetyFilter.apply = original
    s = timer.seconds
    return {
        "rate": updates * rollout / total,
        "env": s["env"] / total,
        "filter": s["filter"] / total,
        "update": s["update"] / total,
        "policy": 1.0 - (s["env"] + s["update"]) / total,
    }


def sampling_ratio(best: dict[str, dict[str, float]]) -> float:
    """Batched / single agent-steps per second of the rollouts alone (update time removed)."""
    b, s = best["batched"], best["single"]
    return (b["rate"] / (1.0 - b["update"])) / (s["rate"] / (1.0 - s["update"]))


def best_of(repeats: int, runs: dict[str, Any]) -> dict[str, dict[str, float]]:
    """Each of ``runs`` (name: a callable returning :func:`run`'s dict), alternating,
    ``repeats`` times: the fastest of each."""
    best: dict[str, dict[str, float]] = {}
    for _ in range(repeats):
        for name, go in runs.items():
            r = go()
            if name not in best or r["rate"] > best[name]["rate"]:
                best[name] = r
    return best


def table(first: str, rows: dict[str, dict[str, float]]) -> list[str]:
    """The rates and time shares of ``rows`` (label: :func:`run`'s dict)."""
    return [
        f"| {first} | agent-steps/s (updates included) | env step | of which filter | policy "
        "forward | PPO update |",
        "|---|---|---|---|---|---|",
        *(
            f"| {label} | {r['rate']:.0f} | {r['env']:.0%} | {r['filter']:.0%} | "
            f"{r['policy']:.0%} | {r['update']:.0%} |"
            for label, r in rows.items()
        ),
    ]


def nominal_section(updates: int, repeats: int) -> list[str]:
    """The crowd config trained with R-ORCA under the residual against move-to-goal under it,
    alternating runs, the best of each."""
    best = best_of(
        repeats,
        {
            nominal: (lambda nominal=nominal: run("batched", updates, "crowd", nominal))
            for nominal in ("move_to_goal", "rorca")
        },
    )
    cfg = configs.resolve(configs.load("crowd"))
    lines = [
        "## The residual's base: R-ORCA against move-to-goal",
        "",
        f"The crowd config ({cfg['env']['num_agents']} agents, {cfg['num_envs']} envs, dt "
        f"{cfg['env']['dt']}, PPO {hyper_note(cfg)}, {rollout_size(cfg)} agent-steps an update) "
        "through `BatchedEnv`, with `env.nominal=move_to_goal` (the config's) and with "
        "`env.nominal=rorca`, alternating, best of each.",
        "",
        *table("env.nominal", best),
    ]
    ratio = best["rorca"]["rate"] / best["move_to_goal"]["rate"]
    return [*lines, "", f"R-ORCA / move-to-goal: **{ratio:.2f}x** the agent-steps per second.", ""]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--updates", type=int, default=4)
    p.add_argument("--repeats", type=int, default=3)
    args = p.parse_args()
    torch.set_num_threads(1)
    best = best_of(
        args.repeats,
        {path: (lambda path=path: run(path, args.updates)) for path in ("batched", "single")},
    )
    ratio = best["batched"]["rate"] / best["single"]["rate"]
    cfg = configs.resolve(configs.load("circular_swap"))
    lines = [
        "# Training throughput: PPO through the batched env vs the single-env path",
        "",
        f"`python -m benchmarks.speed.training_speed --updates {args.updates} "
        f"--repeats {args.repeats}` on {machine(None, 'torch')}, one torch thread.",
        "",
        "circular_swap residual config (6 agents, filter on, dt 0.1), PPO "
        f"({hyper_note(cfg)}), {rollout_size(cfg)} agent-steps an update; best of the "
        "alternating runs. Shares are of wall time; the filter is part of the env step.",
        "",
        *table(
            "path",
            {
                f"BatchedEnv, {cfg['num_envs']} envs": best["batched"],
                "one ParallelEnv": best["single"],
            },
        ),
    ]
    ceiling = 1.0 / best["single"]["update"]
    lines += [
        "",
        f"Batched / single: **{ratio:.1f}x**. Sampling alone (env step and policy forward, "
        f"updates excluded): {sampling_ratio(best):.1f}x. The PPO update is the same work on "
        "both paths (same rollout, epochs and minibatches), so with these hyperparameters no "
        "env, however fast, could make the batched path more than 1 / (the single path's "
        f"update share) = {ceiling:.1f}x faster than the single one.",
        "",
        *nominal_section(args.updates, args.repeats),
    ]
    out = RESULTS / "training_speed.md"
    out.write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
