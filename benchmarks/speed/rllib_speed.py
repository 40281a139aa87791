"""RLlib sampling throughput on the filtered circular game, against the env alone (run in the
``distributed`` venv).

* env alone: ``RSVOMultiAgentEnv`` (our adapter, filter on, residual actions) stepped with fixed
  random actions, in this process;
* RLlib sampling: PPO's env runners (one shared module) with 0 (the driver samples), 1 and 2
  env runners of one env each, and 1 env runner of 4 envs (RLlib's vectorised multi-agent env):
  agent-steps per second of ``sample()``, all runners in parallel, and the share of a runner's
  time that is RLlib's own work (connectors, module inference, episode bookkeeping) rather than
  the env's: ``1 - runner rate / env rate`` per runner;
* PPO with one env runner: agent-steps per second with the updates included.

Best of ``--repeats``. Writes ``benchmarks/results/rllib_speed.md``.

    python -m benchmarks.speed.rllib_speed [--env-steps 1000] [--repeats 3]
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from benchmarks.harness import RESULTS, machine
from rsvo_env.training import config as configs
from rsvo_env.training.rllib_engine import build
from rsvo_env.training.rllib_env import RSVOMultiAgentEnv


def env_alone(cfg: dict, env_steps: int) -> float:
    env = RSVOMultiAgentEnv({"cfg": cfg})
    agents = env.possible_agents
    actions = np.random.default_rng(0).uniform(-1, 1, (64, len(agents), 2)).astype(np.float32)
    env.reset(seed=0)
    t0, done = time.perf_counter(), 0
    for k in range(env_steps):
        _, _, term, trunc, _ = env.step(dict(zip(agents, actions[k % 64], strict=True)))
        if term["__all__"] or trunc["__all__"]:
            env.reset()
        done += 1
    return done * len(agents) / (time.perf_counter() - t0)


def sampling(cfg: dict, runners: int, envs: int, env_steps: int, repeats: int) -> float:
    algo = build(cfg, runners, envs).build_algo()
    n = cfg["env"]["num_agents"]

    def sample() -> int:
        if runners == 0:
            eps = algo.env_runner.sample(num_timesteps=env_steps, random_actions=False)
            return sum(e.env_steps() for e in eps)
        counts = algo.env_runner_group.foreach_env_runner(
            lambda r: sum(e.env_steps() for e in r.sample(num_timesteps=env_steps)),
            local_env_runner=False,
        )
        return sum(counts)

    sample()  # warm-up: compiles, builds episodes
    best = 0.0
    for _ in range(repeats):
        t0 = time.perf_counter()
        steps = sample()
        best = max(best, steps * n / (time.perf_counter() - t0))
    algo.stop()
    return best


def training(cfg: dict, iterations: int) -> float:
    algo = build(cfg, 1, 1).build_algo()
    algo.train()
    t0, steps = time.perf_counter(), 0
    for _ in range(iterations):
        result = algo.train()
        steps += sum(result["env_runners"]["num_agent_steps_sampled"].values())
    rate = steps / (time.perf_counter() - t0)
    algo.stop()
    return rate


def main() -> int:
    import ray
    import torch

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--env-steps", type=int, default=1000)
    p.add_argument("--repeats", type=int, default=3)
    args = p.parse_args()
    torch.set_num_threads(1)
    cfg = configs.resolve(configs.load("circular_swap"), engine="rllib")
    ray.init(include_dashboard=False, log_to_driver=False)
    alone = max(env_alone(cfg, args.env_steps) for _ in range(args.repeats))
    rows = []
    for runners, envs in ((0, 1), (1, 1), (2, 1), (1, 4)):
        rate = sampling(cfg, runners, envs, args.env_steps, args.repeats)
        per_runner = rate / max(runners, 1)
        rows.append((runners, envs, rate, 1.0 - per_runner / alone))
    train_rate = training(cfg, 3)
    ray.shutdown()
    lines = [
        "# RLlib sampling throughput vs the env alone",
        "",
        f"`python -m benchmarks.speed.rllib_speed --env-steps {args.env_steps} --repeats "
        f"{args.repeats}` on {machine(None, 'ray')}, one torch thread. circular_swap config "
        "(6 agents, filter on, "
        "residual actions, dt 0.1).",
        "",
        f"Env alone (our `RSVOMultiAgentEnv`, random actions): **{alone:,.0f} agent-steps/s**.",
        "",
        "| env runners | envs per runner | sampling agent-steps/s | RLlib's share of a "
        "runner's time |",
        "|---|---|---|---|",
        *[f"| {r} | {e} | {rate:,.0f} | {share:.0%} |" for r, e, rate, share in rows],
        "",
        f"PPO with 1 env runner, updates included: {train_rate:,.0f} agent-steps/s.",
        "",
    ]
    out = RESULTS / "rllib_speed.md"
    out.write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
