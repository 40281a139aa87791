"""Copies keep counting: an env copied mid-episode (``copy.deepcopy`` or ``pickle``) goes on
exactly as the original, through truncation and auto-reset, on both after-integration paths
(the fused one and the scenario hooks: the ramp merge, crowds over 64 agents)."""

import copy
import pickle

import numpy as np
import pytest

import rsvo_env
from rsvo_env import wrappers
from rsvo_env.envs.vector import BatchedEnv


def copies(env):
    return [copy.deepcopy(env), pickle.loads(pickle.dumps(env))]


def batched_roll(env, steps):
    out = []
    for _ in range(steps):
        obs, reward, term, trunc, info = env.step(env.nominal_actions())
        episode = {k: v.copy() for k, v in info.items() if k.startswith("episode_")}
        out.append((obs.copy(), reward.copy(), term.copy(), trunc.copy(), episode))
    return out


@pytest.mark.parametrize(
    "scenario,kwargs",
    [
        ("crowd", {"num_agents": 70, "max_steps": 25}),  # the hooks path, over 64 agents
        ("crowd", {"num_agents": 8, "max_steps": 25}),  # the fused path
        ("ramp_merge", {"max_steps": 30}),  # scenario hooks
    ],
)
def test_batched_copy_goes_on_as_the_original(scenario, kwargs):
    env = BatchedEnv(scenario, num_envs=2, **kwargs)
    env.reset(seed=4)
    batched_roll(env, 10)
    twins = copies(env)
    want = batched_roll(env, 40)  # past truncation (max_steps) and its auto-reset
    assert any(step[3].any() for step in want)
    for twin in twins:
        got = batched_roll(twin, 40)
        for a, b in zip(want, got, strict=True):
            for x, y in zip(a[:4], b[:4], strict=True):
                np.testing.assert_array_equal(x, y)
            assert a[4].keys() == b[4].keys()
            for k in a[4]:
                np.testing.assert_array_equal(a[4][k], b[4][k], err_msg=k)


def parallel_roll(env, steps):
    out = []
    for _ in range(steps):
        if not env.agents:
            break
        obs, rew, term, trunc, infos = env.step(env.unwrapped.nominal_actions())
        out.append((obs, rew, term, trunc, infos))
    return out, env.unwrapped.episode_metrics


@pytest.mark.parametrize(
    "scenario,kwargs",
    [("ramp_merge", {"max_steps": 30}), ("circular_swap", {"max_steps": 40})],
)
def test_parallel_copy_goes_on_as_the_original(scenario, kwargs):
    env = rsvo_env.parallel_env(scenario, **kwargs)
    env.reset(seed=1)
    parallel_roll(env, 10)
    twins = copies(env)
    want, want_metrics = parallel_roll(env, 100)
    assert len(want) == kwargs["max_steps"] - 10  # truncated at max_steps
    for twin in twins:
        got, got_metrics = parallel_roll(twin, 100)
        assert len(got) == len(want)
        for a, b in zip(want, got, strict=True):
            for agent in a[0]:
                np.testing.assert_array_equal(a[0][agent], b[0][agent])
                assert a[1][agent] == b[1][agent]
                assert (a[2][agent], a[3][agent]) == (b[2][agent], b[3][agent])
                info_a, info_b = a[4][agent], b[4][agent]
                for k in info_a:
                    np.testing.assert_array_equal(info_a[k], info_b[k], err_msg=k)
        for k, v in want_metrics.items():
            np.testing.assert_array_equal(v, got_metrics[k], err_msg=k)


def test_copied_metrics_count_in_the_copy():
    """The counters of a copy are its own and advance with it (not with the original)."""
    env = BatchedEnv("crowd", num_envs=1, num_agents=70, max_steps=50)
    env.reset(seed=0)
    batched_roll(env, 3)
    twin = copy.deepcopy(env)
    batched_roll(twin, 5)
    assert int(twin.sim.metrics.steps[0]) == 8
    assert int(env.sim.metrics.steps[0]) == 3


def test_gymnasium_and_sb3_copies_go_on_as_the_original():
    """The same through ``gymnasium.make`` (its TimeLimit and our truncation) and SB3's VecEnv."""
    import gymnasium

    env = gymnasium.make("rsvo/Crowd-v0", num_agents=70, max_steps=30, max_episode_steps=30)
    env.reset(seed=0)
    for _ in range(10):
        env.step(env.unwrapped.nominal_action())

    def roll(e):
        out = []
        for _ in range(25):
            obs, reward, term, trunc, _ = e.step(e.unwrapped.nominal_action())
            out.append(np.r_[obs, reward, term, trunc])
            if term or trunc:
                out.append(e.reset()[0])
        return out

    twins = copies(env)
    want = roll(env)
    for twin in twins:
        for a, b in zip(want, roll(twin), strict=True):
            np.testing.assert_array_equal(a, b)
    venv = wrappers.SB3VecEnv(BatchedEnv("crowd", num_envs=2, num_agents=70, max_steps=20))
    venv.seed(0)
    venv.reset()
    act = np.zeros((venv.num_envs, 2), np.float32)
    for _ in range(5):
        venv.step(act)
    twins = copies(venv)
    want = [venv.step(act) for _ in range(30)]
    for twin in twins:
        for a, b in zip(want, [twin.step(act) for _ in range(30)], strict=True):
            for x, y in zip(a[:3], b[:3], strict=True):
                np.testing.assert_array_equal(x, y)
