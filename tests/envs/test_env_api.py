"""PettingZoo's own conformance tests on every scenario, bare and behind the filter."""

import numpy as np
import pytest
from pettingzoo.test import api_test, parallel_api_test, render_test
from pettingzoo.utils.conversions import parallel_to_aec

import rsvo_env
from rsvo_env import wrappers
from tests.support.checkers import checked

SMALL = {
    "position_swap": {"safety_radius": 0.5, "u_max": 1.0, "max_steps": 300},
    "circular_swap": {"num_agents": 4, "circle_radius": 3.0, "max_steps": 300},
    "ramp_merge": {"start_distance": 30.0, "v0": 10.0, "max_steps": 300},
    "crowd": {"num_agents": 5, "max_steps": 300},
    "doorway": {"num_agents": 4, "max_steps": 300},
    "obstacle_field": {"num_agents": 4, "num_circles": 4, "max_steps": 300},
    "unicycle_crowd": {"num_agents": 5, "max_steps": 300},
}
CASES = [(name, {}) for name in SMALL] + list(SMALL.items())
IDS = [f"{n}-{'custom' if kw else 'default'}" for n, kw in CASES]


def make(name, kwargs, filtered, **extra):
    env = rsvo_env.parallel_env(name, **kwargs, **extra)
    return wrappers.RCBFSafetyFilter(env) if filtered else env


@pytest.mark.parametrize("filtered", [False, True], ids=["bare", "filtered"])
@pytest.mark.parametrize("name,kwargs", CASES, ids=IDS)
def test_pettingzoo_api(name, kwargs, filtered):
    checked(parallel_api_test, make(name, kwargs, filtered), num_cycles=400)
    checked(api_test, parallel_to_aec(make(name, kwargs, filtered)), num_cycles=400)


@pytest.mark.parametrize("filtered", [False, True], ids=["bare", "filtered"])
@pytest.mark.parametrize("name,kwargs", CASES, ids=IDS)
def test_render_api(name, kwargs, filtered):
    render_test(
        lambda render_mode=None: parallel_to_aec(
            make(name, kwargs, filtered, render_mode=render_mode)
        )
    )


@pytest.mark.parametrize("filtered", [False, True], ids=["bare", "filtered"])
@pytest.mark.parametrize("name,kwargs", CASES, ids=IDS)
def test_observations_stay_in_space(name, kwargs, filtered):
    env = make(name, kwargs, filtered)
    rng = np.random.default_rng(0)
    obs, _ = env.reset(seed=1)
    space = env.observation_space(env.possible_agents[0])
    for _ in range(1000):
        if not env.agents:
            obs, _ = env.reset()
        for agent, o in obs.items():
            assert space.contains(o), (agent, o[~((o >= space.low) & (o <= space.high))])
        actions = {a: rng.uniform(-1, 1, 2).astype(np.float32) for a in env.agents}
        obs, *_ = env.step(actions)


def test_spaces_are_cached_and_shaped():
    env = rsvo_env.parallel_env("crowd", num_agents=9, num_obs_neighbors=3)
    a = env.possible_agents[0]
    assert env.observation_space(a) is env.observation_space(a)
    assert env.action_space(a) is env.action_space(a)
    assert env.observation_space(a).shape == (5 + 10 * 3,)
    assert np.all(np.isfinite(env.observation_space(a).high))
    assert env.action_space(a).shape == (2,)


def test_aec_factory():
    env = rsvo_env.env("position_swap")
    env.reset(seed=0)
    assert env.agent_selection == "agent_0"


def test_goal_frame_makes_rotated_scenarios_the_same_task():
    """In the goal frame every circular-swap agent sees the same goal offset at the start."""
    env = rsvo_env.parallel_env("circular_swap", frame="goal")
    obs, _ = env.reset(seed=0)
    first = obs["agent_0"][:2]
    for o in obs.values():
        np.testing.assert_allclose(o[:2], first, atol=1e-5)
    # and the nominal actions, stepped in the goal frame, move agents toward their goals
    before = env.unwrapped.world.positions.copy()
    env.step(env.unwrapped.nominal_actions())
    w = env.unwrapped.world
    assert np.all(
        np.linalg.norm(w.positions - w.goals, axis=1) < np.linalg.norm(before - w.goals, axis=1)
    )
