"""The global state (``state()`` / ``state_space``): PettingZoo's own state checks, and every
agent's observation rebuilt from the state alone."""

import warnings

import numpy as np
import pytest
from pettingzoo.test import parallel_api_test, state_test

import rsvo_env
from rsvo_env.envs import global_state
from rsvo_env.envs.registration import IDS
from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.responsibility.svo import responsibility_weight
from tests.support.checkers import checked


@pytest.mark.parametrize("scenario", list(IDS.values()))
def test_pettingzoo_state_test_parallel_and_aec(scenario):
    # PettingZoo's state_test warns on what it finds odd (all zeros, NaN, inf): none here
    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)
        state_test(
            rsvo_env.env(scenario),
            rsvo_env.parallel_env(scenario),
            num_cycles=100,
        )
    checked(parallel_api_test, rsvo_env.parallel_env(scenario), num_cycles=50)


def unpack(sim, state):
    """(N, F) agent blocks and (O, 5) obstacles of one state vector."""
    F = len(global_state.agent_fields(sim))
    agents = state[: sim.n * F].reshape(sim.n, F)
    return agents, state[sim.n * F :].reshape(-1, 5)


@pytest.mark.parametrize(
    "scenario, kwargs",
    [("crowd", {"num_agents": 9}), ("circular_swap", {}), ("obstacle_field", {})],
)
def test_observations_rebuilt_from_the_state(scenario, kwargs):
    env = rsvo_env.parallel_env(scenario, **kwargs)
    obs, _ = env.reset(seed=3)
    sim = env.unwrapped.sim
    rng = np.random.default_rng(0)
    played = 0
    for _ in range(40):
        played += 1
        agents, obstacles = unpack(sim, env.state())
        x, v, g, theta, r = (
            agents[:, :2],
            agents[:, 2:4],
            agents[:, 4:6],
            agents[:, 6],
            agents[:, 7],
        )
        np.testing.assert_allclose(obstacles, sim.state.obstacles[0], rtol=1e-6)
        K = sim.k
        for i, a in enumerate(env.possible_agents):
            o = obs[a]
            np.testing.assert_allclose(o[0:2], g[i] - x[i], rtol=1e-5, atol=1e-4)
            np.testing.assert_allclose(o[2:4], v[i], rtol=1e-5, atol=1e-5)
            assert o[4] == pytest.approx(theta[i])
            # the K nearest by centre distance (equidistant ones in either order)
            d = np.linalg.norm(x - x[i], axis=-1)
            d[i] = np.inf
            nearest = np.sort(d)[:K]
            blocks = o[5 : 5 + 10 * K].reshape(K, 10)
            for k, b in enumerate(blocks):
                # the agent this block describes: the one at the block's relative position
                j = int(np.argmin(np.linalg.norm(x - x[i] - b[0:2], axis=-1)))
                assert d[j] == pytest.approx(nearest[k], rel=1e-5)
                np.testing.assert_allclose(b[0:2], x[j] - x[i], rtol=1e-5, atol=1e-4)
                np.testing.assert_allclose(b[2:4], v[j] - v[i], rtol=1e-5, atol=1e-5)
                np.testing.assert_allclose(b[4:6], g[j] - x[i], rtol=1e-5, atol=1e-4)
                assert b[6] == pytest.approx(responsibility_weight(theta[i], theta[j]), abs=1e-6)
                assert b[7] == pytest.approx(theta[j])
                assert b[8] == pytest.approx(d[j] - r[i] - r[j], abs=1e-4)
                assert b[9] == 1.0
        actions = {a: rng.uniform(-1, 1, 2).astype(np.float32) for a in env.agents}
        obs, *_ = env.step(actions)
        if not env.agents:
            break
    assert played >= 20


def test_unicycle_state_has_headings_in_range():
    env = rsvo_env.parallel_env("unicycle_crowd", num_agents=5)
    env.reset(seed=0)
    sim = env.sim
    assert global_state.agent_fields(sim)[-1] == "heading"
    for _ in range(30):
        env.step({a: np.array([1.0, 1.0], np.float32) for a in env.agents})
        agents, _ = unpack(sim, env.state())
        h = sim.state.headings[0]
        np.testing.assert_allclose(np.cos(agents[:, 8]), np.cos(h), atol=1e-5)
        np.testing.assert_allclose(np.sin(agents[:, 8]), np.sin(h), atol=1e-5)
        assert env.state_space.contains(env.state())


def test_batched_state_equals_single_envs():
    batched = BatchedEnv("crowd", num_envs=3, num_agents=6)
    batched.reset(seed=10)
    singles = [rsvo_env.parallel_env("crowd", num_agents=6) for _ in range(3)]
    for e, env in enumerate(singles):
        env.reset(seed=10 + e)
    rng = np.random.default_rng(1)
    for _ in range(10):
        a = rng.uniform(-1, 1, (3, 6, 2)).astype(np.float32)
        batched.step(a)
        for e, env in enumerate(singles):
            env.step(dict(zip(env.possible_agents, a[e], strict=True)))
        s = batched.state()
        assert batched.state_space.contains(s)
        for e, env in enumerate(singles):
            np.testing.assert_array_equal(s[e], env.state())


def test_state_before_reset_is_refused():
    with pytest.raises(RuntimeError, match="reset"):
        rsvo_env.parallel_env("crowd").state()
    with pytest.raises(RuntimeError, match="reset"):
        BatchedEnv("crowd", num_envs=2).state()
