"""What every benchmark shares: the machine line its results file opens with, timed blocks that
alternate between the cases compared (so a change of load on a shared machine falls on all of
them alike), and the results writer. Speeds are ratios within one run, never absolute claims."""

from __future__ import annotations

import os
import platform
import time
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"


def machine(threads: int | None = None, *packages: str) -> str:
    """The machine a run measured: processor, cores, Python, numpy (and ``packages`` by name,
    e.g. ``"numba"``), and ``threads`` where the run pinned a number of them."""
    import importlib

    parts = [
        platform.processor() or platform.machine(),
        f"{os.cpu_count()} cores",
        f"Python {platform.python_version()}",
        f"numpy {np.__version__}",
    ]
    parts += [f"{name} {importlib.import_module(name).__version__}" for name in packages]
    if threads is not None:
        parts.append("one thread" if threads == 1 else f"{threads} threads")
    return ", ".join(parts)


def alternate(calls: dict[str, Callable[[], object]], blocks: int) -> dict[str, float]:
    """The best wall time (s) of each named call over ``blocks`` rounds, the calls alternating
    within each round; each is called once first (numba compiles, caches fill)."""
    for call in calls.values():
        call()
    best = dict.fromkeys(calls, float("inf"))
    for _ in range(blocks):
        for name, call in calls.items():
            t0 = time.perf_counter()
            call()
            best[name] = min(best[name], time.perf_counter() - t0)
    return best


def rate(step: Callable[[], object], agents: int, seconds: float) -> float:
    """Agent-steps per second of ``step`` (``agents`` agent-steps a call) over ``seconds``."""
    steps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        step()
        steps += 1
    return agents * steps / (time.perf_counter() - t0)


def best_rates(
    makers: dict[str, Callable[[], tuple[Callable[[], object], int]]], seconds: float, repeats: int
) -> dict[str, float]:
    """The best :func:`rate` of each named case over ``repeats`` rounds, the cases alternating;
    each maker builds a case's step and its agents a step."""
    built = {name: make() for name, make in makers.items()}
    for step, _ in built.values():
        step()  # warm: numba compiles, caches fill
    rates = dict.fromkeys(built, 0.0)
    for _ in range(repeats):
        for name, (step, agents) in built.items():
            rates[name] = max(rates[name], rate(step, agents, seconds))
    return rates


def write(path: str | Path, lines: Iterable[str]) -> Path:
    """Write a results file (``lines`` joined, one newline at the end) and say where."""
    path = Path(path)
    path.write_text("\n".join(lines).rstrip("\n") + "\n")
    print(f"wrote {path}")
    return path
