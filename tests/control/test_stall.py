"""The stall clock (``stall_clock=``): a plain reference, its place in the observation, resets,
units, and bad values."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import rsvo_env
from rsvo_env.control.stall import PROGRESS, StallClock
from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.sim import observation
from tests.support.checkers import checked


def reference_steps(distances: np.ndarray, at_goal: np.ndarray, radius: float) -> np.ndarray:
    """Steps since the last progress after each step, one agent at a time, as the module's
    docstring defines it. ``distances`` (T + 1, N): at the reset, then after each step."""
    T, n = distances.shape[0] - 1, distances.shape[1]
    out = np.zeros((T, n), dtype=np.int64)
    for i in range(n):
        best, steps = distances[0, i], 0
        for t in range(T):
            d = distances[t + 1, i]
            if at_goal[t, i] or d <= best - PROGRESS * radius:
                best, steps = d, 0
            else:
                steps += 1
            out[t, i] = steps
    return out


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    scale=st.sampled_from([1e-3, 1.0, 1e3]),
    drift=st.floats(-0.05, 0.05),
)
def test_the_clock_counts_the_steps_since_the_last_progress_in_any_unit(seed, scale, drift):
    rng = np.random.default_rng(seed)
    T, n = 60, 5
    # random walks toward (or away from) the goal, some agents standing still for a while
    steps = rng.normal(drift, 0.03, (T, n)) * rng.integers(0, 2, (T, n))
    distances = np.abs(3.0 + np.concatenate([np.zeros((1, n)), np.cumsum(steps, 0)])) * scale
    at_goal = rng.random((T, n)) < 0.05
    want = reference_steps(distances, at_goal, 1.0 * scale)
    clock = StallClock.create(4, 1, n)
    clock.reset(np.array([0]), distances[:1])
    for t in range(T):
        # on the x axis, goals at the origin: the distance is x exactly (sqrt of a square)
        x = np.stack([distances[t + 1], np.zeros(n)], axis=-1)[None]
        clock.tick(x, np.zeros_like(x), at_goal[t][None], 1.0 * scale)
        np.testing.assert_array_equal(clock.steps[0], want[t])
        np.testing.assert_array_equal(clock.value()[0], want[t] / 4)
    assert want.max() > 0 and (want == 0).any()  # the walk both stalls and progresses


def crowd(**kw) -> BatchedEnv:
    return BatchedEnv("crowd", num_agents=6, dt=0.1, gamma=10.0, num_obs_neighbors=3, **kw)


def test_the_clock_sits_between_the_own_features_and_the_neighbours():
    """Same seed and actions with and without the clock: the clock is one inserted column."""
    plain, timed = crowd(num_envs=2), crowd(num_envs=2, stall_clock=10)
    assert timed.single_observation_space.shape == (observation.size(3, stall=True),)
    assert observation.size(3, stall=True) == observation.size(3) + 1
    a, _ = plain.reset(seed=5)
    b, _ = timed.reset(seed=5)
    rng = np.random.default_rng(1)
    for _ in range(40):
        np.testing.assert_array_equal(b[..., :5], a[..., :5])
        np.testing.assert_array_equal(b[..., 6:], a[..., 5:])
        assert timed.observation_space.contains(b)
        act = rng.uniform(-1, 1, (2, 6, 2)) * 0.3
        a, *_ = plain.step(act)
        b, *_ = timed.step(act)


def test_an_agent_held_still_stalls_and_one_moving_to_its_goal_does_not():
    # move-to-goal: the command itself, unobstructed (R-ORCA would slow it for the crossings ahead)
    env = crowd(num_envs=1, stall_clock=10, nominal="move_to_goal")
    env.reset(seed=2)
    hold = np.zeros((1, 6, 2))
    for t in range(1, 16):
        obs, *_ = env.step(hold)
        at_goal = env.sim.state.at_goal[0]
        np.testing.assert_allclose(obs[0, ~at_goal, 5], t / 10, rtol=1e-6)
        np.testing.assert_array_equal(obs[0, at_goal, 5], 0.0)
    # the scripted command, unobstructed at first, makes progress at once
    obs, *_ = env.step(env.nominal_actions())
    moving = np.linalg.norm(env.sim.state.velocities[0], axis=-1) > 0.5 * env.scenario.u_max
    assert moving.any()
    np.testing.assert_array_equal(obs[0, moving, 5], 0.0)


def test_a_new_episode_starts_its_clock_at_zero():
    env = crowd(num_envs=3, stall_clock=5, max_steps=12)
    env.reset(seed=0)
    hold = np.zeros((3, 6, 2))
    for _ in range(11):
        obs, _, _, truncated, info = env.step(hold)
    assert not truncated.any() and obs[..., 5].max() >= 2.0
    obs, _, _, truncated, info = env.step(hold)
    assert truncated.all()
    assert info["final_obs"][..., 5].max() >= 2.0  # the ended episode's clock, kept
    np.testing.assert_array_equal(obs[..., 5], 0.0)


def test_the_parallel_env_observes_the_clock_too():
    env = rsvo_env.parallel_env("crowd", num_agents=4, num_obs_neighbors=2, stall_clock=3)
    obs, _ = env.reset(seed=1)
    space = env.observation_space("agent_0")
    assert space.shape == (observation.size(2, stall=True),)
    assert space.high[5] == pytest.approx(env.unwrapped.max_steps / 3)
    obs, *_ = env.step({a: np.zeros(2) for a in env.agents})
    assert all(space.contains(o) for o in obs.values())


@pytest.mark.parametrize("bad", [0, -3, 2.5, True, "50", float("nan"), 1j])
def test_a_bad_stall_clock_is_refused_by_name(bad):
    with pytest.raises(ValueError, match="stall_clock"):
        crowd(stall_clock=bad)
    with pytest.raises(ValueError, match="stall_clock"):
        rsvo_env.parallel_env("crowd", num_agents=4, stall_clock=bad)


def test_pettingzoo_finds_nothing_wrong_with_the_clock_observed():
    from pettingzoo.test import parallel_api_test

    env = rsvo_env.parallel_env("crowd", num_agents=4, num_obs_neighbors=2, stall_clock=3)
    checked(parallel_api_test, env, num_cycles=200)
