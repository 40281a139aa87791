"""One safety default (docs/environments.md): every entry point filters unless it is given
``safety_filter=False``. A head-on position swap driven straight at the goals keeps its distance
through each with default arguments, and collides through each with the filter off."""

from __future__ import annotations

import gymnasium
import numpy as np
import pettingzoo
import pytest

import rsvo_env
from rsvo_env.envs.registration import HAS_REGISTRY

STEPS = 300
ID = "rsvo/PositionSwap-v0"


def straight(sim) -> np.ndarray:
    """(E, N, 2): each agent's unit action straight at its goal (full speed)."""
    d = sim.state.goals - sim.state.positions
    n = np.linalg.norm(d, axis=-1, keepdims=True)
    return np.divide(d, n, out=np.zeros_like(d), where=n > 0)


def gap(sim) -> float:
    """The pair's distance over the safety radius, env 0."""
    x = sim.state.positions[0]
    return float(np.linalg.norm(x[0] - x[1]) / sim.scenario.params["safety_radius"])


def parallel(env) -> float:
    env.reset(seed=0)
    sim, least = env.unwrapped.sim, np.inf
    for _ in range(STEPS):
        u = straight(sim)[0]
        env.step({a: u[i] for i, a in enumerate(env.possible_agents)})
        least = min(least, gap(sim))
    return least


def batched(env) -> float:
    env.reset(seed=0)
    least = np.inf
    for _ in range(STEPS):
        env.step(straight(env.sim))
        least = min(least, gap(env.sim))
    return least


def joint(env) -> float:
    env.reset(seed=0)
    sim, least = env.unwrapped.base.sim, np.inf
    for _ in range(STEPS):
        env.step(straight(sim)[0].reshape(-1).astype(np.float32))
        least = min(least, gap(sim))
    return least


ENTRY_POINTS = {
    "rsvo_env.parallel_env": lambda **kw: parallel(rsvo_env.parallel_env("position_swap", **kw)),
    "BatchedEnv": lambda **kw: batched(rsvo_env.BatchedEnv("position_swap", **kw)),
    "gymnasium.make": lambda **kw: joint(gymnasium.make(ID, **kw)),
    "pettingzoo.make": lambda **kw: parallel(pettingzoo.make("parallel", ID, **kw)),
}


@pytest.mark.parametrize("entry", list(ENTRY_POINTS))
def test_every_entry_point_filters_by_default(entry):
    if entry == "pettingzoo.make" and not HAS_REGISTRY:
        pytest.fail("this PettingZoo has no registry (the dev extra installs one that has)")
    assert ENTRY_POINTS[entry]() >= 1 - 1e-9


@pytest.mark.parametrize("entry", list(ENTRY_POINTS))
def test_every_entry_point_accepts_safety_filter_false_and_then_collides(entry):
    assert ENTRY_POINTS[entry](safety_filter=False) < 0.5


def test_the_aec_form_filters_by_default_too():
    env = rsvo_env.env("position_swap")
    assert len(env.unwrapped.sim.filters) == 1
    assert rsvo_env.env("position_swap", safety_filter=False).unwrapped.sim.filters == []
