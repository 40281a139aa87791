"""The single env's step cost against a frozen numpy reference, timed in one process.

``single(n, filtered)`` steps one ``RSVOParallelEnv`` of ``crowd`` (PettingZoo dicts, scripted
nominal actions computed every step, episodes reset as they end), with or without
``RCBFSafetyFilter``; ``reference(n)`` is the bare numpy work every step must do at least
(x += dt u and one dense nearest-neighbour query, a KD-tree above 64 agents), frozen here so the
yardstick does not move with the library.

This module imports only ``rsvo_env`` and ``wrappers`` through the API they have had since the
first milestone, so ``python -m benchmarks.speed.env_speed --baseline REV`` runs it on an older
checkout of the library too: each run's ratio is against the same reference, timed in that
run's own process.

    python -m benchmarks.speed.single_env_speed [--agents 6] [--seconds 1] [--repeats 5]

prints one JSON line: agent-steps per second of ``bare``, ``filtered`` and ``reference``.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
from collections.abc import Callable

import numpy as np

import rsvo_env
from benchmarks.harness import best_rates


def single_env(scenario: str, filtered: bool, filter_kwargs: dict | None = None, **kwargs):
    """The single env, filtered or bare, in this library or an older one (the comparisons run
    earlier revisions): from 1.0 every env filters unless ``safety_filter=False`` and takes the
    filter's keywords; before it, ``parallel_env`` was bare and the filter a wrapper of the
    top-level package ``wrappers``."""
    given = filter_kwargs or {} if filtered else {}
    try:
        return rsvo_env.parallel_env(scenario, safety_filter=filtered, **given, **kwargs)
    except TypeError as exc:
        if "safety_filter" not in str(exc):
            raise
    env = rsvo_env.parallel_env(scenario, **kwargs)
    if filtered:  # a library before 1.0: its top-level ``wrappers`` (imported by name)
        env = importlib.import_module("wrappers").RCBFSafetyFilter(env, **given)
    return env


def crowd(n: int, filtered: bool):
    """The crowd under move-to-goal, the scripted work these figures have always timed (an
    older library, before R-ORCA, has no ``nominal`` and is move-to-goal already)."""
    try:
        return single_env("crowd", filtered, num_agents=n, nominal="move_to_goal")
    except TypeError:
        return single_env("crowd", filtered, num_agents=n)


def single(n: int, filtered: bool) -> tuple[Callable, int]:
    env = crowd(n, filtered)
    env.reset(seed=0)
    base = env.unwrapped

    def step() -> None:
        if not env.agents:
            env.reset()
        env.step(base.nominal_actions())

    return step, n


def reference(n: int) -> tuple[Callable, int]:
    """The bare numpy work of a step: the Euler update and a dense nearest-neighbour query."""
    env = crowd(n)
    env.reset(seed=0)
    state = {"x": env.unwrapped.world.positions.copy()}
    u = env.unwrapped.nominal_controls()

    def step() -> None:
        x = state["x"] = state["x"] + 0.01 * u
        if n <= 64:
            diff = x[:, None, :] - x[None, :, :]
            d2 = np.einsum("ijk,ijk->ij", diff, diff)
            np.fill_diagonal(d2, np.inf)
            idx = np.argsort(d2, axis=1, kind="stable")[:, :1]
            np.sqrt(np.take_along_axis(d2, idx, axis=1))
        else:
            from scipy.spatial import cKDTree

            cKDTree(x).query(x, k=2)

    return step, n


def rates(n: int, seconds: float, repeats: int) -> dict[str, float]:
    """Agent-steps per second of the bare env, the filtered env and the reference, at n agents."""
    return best_rates(
        {
            "reference": lambda: reference(n),
            "bare": lambda: single(n, False),
            "filtered": lambda: single(n, True),
        },
        seconds,
        repeats,
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--agents", type=int, default=6)
    ap.add_argument("--seconds", type=float, default=1.0, help="length of one burst")
    ap.add_argument("--repeats", type=int, default=5, help="bursts per benchmark")
    args = ap.parse_args(argv)
    print(json.dumps(rates(args.agents, args.seconds, args.repeats)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
