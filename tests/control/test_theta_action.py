"""Theta as an action (rsvo_env.control.theta_action): the map, the spaces, the refusals,
determinism
against single envs, and safety under random and adversarial personalities changed every step."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import rsvo_env
from rsvo_env import wrappers
from rsvo_env.control.theta_action import DEFAULT_RANGE, ThetaAction
from rsvo_env.envs.vector import BatchedEnv
from tests.envs.test_batched import check_batch_equals_singles
from tests.support.checkers import checked

CROWD = {"dt": 0.1, "gamma": 10.0}  # gamma dt = 1: the largest step the guarantee allows


@given(st.floats(1e-6, 1e3), st.floats(1.001, 1e6), st.floats(-1.0, 1.0, allow_subnormal=False))
def test_the_log_map_and_its_inverse(low, ratio, a):
    m = ThetaAction(low, low * ratio)
    theta = m.theta(np.array(a))
    assert m.theta_min * (1 - 1e-12) <= theta <= m.theta_max * (1 + 1e-12)
    # the inverse returns the action to the rounding of the logs, relative to the range's
    span = np.log(m.theta_max) - np.log(m.theta_min)
    scale = 1.0 + abs(np.log(m.theta_min)) + abs(np.log(m.theta_max))
    assert abs(m.action(theta) - a) <= 1e-14 * scale / span
    assert m.theta(np.array(-1.0)) == pytest.approx(m.theta_min, rel=1e-12)
    assert m.theta(np.array(1.0)) == pytest.approx(m.theta_max, rel=1e-12)
    # the midpoint is the geometric mean; outside [-1, 1] is clipped, as a norm is
    assert m.theta(np.array(0.0)) == pytest.approx(np.sqrt(m.theta_min * m.theta_max), rel=1e-12)
    assert m.theta(np.array(7.0)) == m.theta(np.array(1.0))


def test_spaces_nominal_and_signals():
    env = BatchedEnv("crowd", num_envs=2, theta_action=True, num_agents=6)
    assert env.single_action_space.shape == (3,)
    assert env.action_space.shape == (2, 6, 3)
    env.reset(seed=0, options={"theta": np.full(6, 2.0)})
    nominal = env.nominal_actions()
    assert nominal.shape == (2, 6, 3)
    # the scripted controller's theta component keeps each agent's theta
    _, _, _, _, info = env.step(nominal)
    assert np.allclose(info["theta"], 2.0, rtol=1e-6)
    obs, _, _, _, info = env.step(np.concatenate([nominal[..., :2], -np.ones((2, 6, 1))], -1))
    assert np.allclose(info["theta"], DEFAULT_RANGE[0])
    # the observation carries the agent's and its neighbours' current scores
    assert np.allclose(obs[..., 4], DEFAULT_RANGE[0])
    par = rsvo_env.parallel_env("crowd", num_agents=4, theta_action=True)
    assert par.action_space("agent_0").shape == (3,)
    assert BatchedEnv("crowd", num_agents=4).single_action_space.shape == (2,)


def test_pettingzoo_and_gymnasium_checkers_pass():
    from gymnasium.utils.env_checker import check_env
    from pettingzoo.test import api_test, parallel_api_test
    from pettingzoo.utils.conversions import parallel_to_aec

    def make():
        env = rsvo_env.parallel_env("crowd", num_agents=5, max_steps=200, theta_action=True)
        return wrappers.RCBFSafetyFilter(env)

    checked(parallel_api_test, make(), num_cycles=200)
    checked(api_test, parallel_to_aec(make()), num_cycles=200)
    joint = wrappers.JointControlEnv("circular_swap", num_agents=4, theta_action=True)
    assert joint.action_space.shape == (12,)
    check_env(joint, skip_render_check=True)


@pytest.mark.parametrize(
    "kwargs,error,pattern",
    [
        ({"theta_action": "yes"}, ValueError, "theta_action"),
        ({"theta_action": 1}, ValueError, "theta_action"),
        ({"theta_action_range": (1.0, 2.0)}, TypeError, "needs theta_action=True"),
        ({"theta_action": True, "theta_action_range": (0.0, 2.0)}, ValueError, "0 < low"),
        ({"theta_action": True, "theta_action_range": (3.0, 2.0)}, ValueError, "low <= high"),
        ({"theta_action": True, "theta_action_range": (1.0, np.nan)}, ValueError, "range"),
        ({"theta_action": True, "theta_action_range": "ab"}, ValueError, "theta_action_range"),
        ({"theta_action": True, "theta_action_range": (1.0, 5e3)}, ValueError, "theta_max"),
    ],
)
def test_bad_keywords_are_refused_by_name(kwargs, error, pattern):
    with pytest.raises(error, match=pattern):
        BatchedEnv("crowd", num_agents=4, **kwargs)


def test_bad_actions_are_refused_and_change_nothing():
    env = BatchedEnv("crowd", num_envs=2, theta_action=True, num_agents=4)
    env.reset(seed=3)
    before = env.sim.state.theta.copy(), env.sim.state.positions.copy()
    with pytest.raises(ValueError, match=r"expected \(2, 4, 3\)"):
        env.step(np.zeros((2, 4, 2)))
    bad = np.zeros((2, 4, 3))
    bad[1, 2, 2] = np.nan
    with pytest.raises(ValueError, match=r"env 1, agent 2"):
        env.step(bad)
    assert np.array_equal(env.sim.state.theta, before[0])
    assert np.array_equal(env.sim.state.positions, before[1])
    par = rsvo_env.parallel_env("crowd", num_agents=3, theta_action=True)
    par.reset(seed=0)
    with pytest.raises(ValueError, match="agent_1"):
        par.step({"agent_0": np.zeros(3), "agent_1": np.zeros(2), "agent_2": np.zeros(3)})


@pytest.mark.parametrize("name", ["circular_swap", "crowd", "doorway", "unicycle_crowd"])
def test_batch_equals_single_envs_bit_for_bit_with_theta_actions(name):
    check_batch_equals_singles(name, True, {"max_steps": 70, "theta_action": True}, 300)


def test_large_crowd_batch_equals_single_envs_bit_for_bit_with_theta_actions():
    """Beyond the dense size: the grid search's floors follow the scores of every step."""
    kwargs = {"max_steps": 25, "num_agents": 90, "theta_action": True}
    check_batch_equals_singles("crowd", True, kwargs, 80)


def adversarial(env, rng, strategy):
    """Each step's actions: the scripted command toward the goal, or straight at the nearest
    neighbour, with theta components chosen by ``strategy``."""
    s = env.sim.state
    E, N = s.theta.shape
    nominal = env.nominal_actions()[..., :2].astype(np.float64)
    if strategy == "uniform":
        return np.concatenate([nominal, rng.uniform(-1, 1, (E, N, 1))], -1)
    if strategy == "bang_bang":  # every agent at an extreme, redrawn every step
        return np.concatenate([nominal, rng.choice([-1.0, 1.0], (E, N, 1))], -1)
    # "worst": every agent drives at its nearest neighbour at full speed, and the one of each
    # pair closing faster is the egoist, the other the altruist (the weights most lopsided
    # where the closing is fastest); the roles swap whenever the closing speeds do
    j = s.neighbors[..., 0]
    gap = np.take_along_axis(s.positions, j[..., None], axis=1) - s.positions
    toward = gap / np.linalg.norm(gap, axis=-1, keepdims=True)
    push = rng.uniform(0.5, 1.0, (E, N, 1)) * toward
    closing = (push * toward).sum(-1)
    other = np.take_along_axis(closing, j, axis=1)
    a_theta = np.where(closing >= other, -1.0, 1.0)
    return np.concatenate([push, a_theta[..., None]], -1)


@pytest.mark.parametrize(
    "n,steps,theta_range",
    [(12, 300, None), (100, 150, None), (1000, 40, None), (12, 300, (1e-3, 1e3)),
     (1500, 15, (1e-3, 1e3))],
)  # fmt: skip
@pytest.mark.parametrize("strategy", ["uniform", "bang_bang", "worst"])
def test_theta_changed_every_step_never_collides(n, steps, theta_range, strategy):
    """Random and adversarial theta actions, changed every step: no pair closer than R, no
    infeasible QP (the single integrator's QP always has u = 0 while h >= 0)."""
    E = 2 if n <= 100 else 1
    env = BatchedEnv(
        "crowd",
        num_envs=E,
        num_agents=n,
        theta_action=True,
        theta_action_range=theta_range,
        max_steps=steps + 1,
        **CROWD,
    )
    env.reset(seed=n)
    rng = np.random.default_rng(n)
    R = env.scenario.params["safety_radius"]
    changed, closest = 0, np.inf
    for _ in range(steps):
        before = env.sim.state.theta.copy()
        _, _, _, _, info = env.step(adversarial(env, rng, strategy))
        changed += int((info["theta"] != before).any())
        closest = min(closest, info["min_distance"].min())
        assert info["min_distance"].min() >= R * (1 - 1e-9)
        assert info["feasible"].all() and not info["cost"].any()
    assert changed == steps
    if strategy == "worst":  # the adversary presses pairs into contact (unfiltered: overlap)
        assert closest <= R * (1 + 1e-6)
    assert (info["episode_collision_steps"] == 0).all()
    assert (info["episode_infeasible"] == 0).all()


@pytest.mark.parametrize("scale", [1e-3, 1e3])
@pytest.mark.parametrize("strategy", ["bang_bang", "worst"])
def test_theta_actions_keep_the_guarantee_in_any_units(scale, strategy):
    """The crowd of 100 in millimetres and in kilometres (every length scaled: radius, speed
    limit, goal tolerance; time not): theta redrawn every step over (1e-3, 1e3), the same
    margin relative to R, and the adversary still presses pairs into contact."""
    env = BatchedEnv(
        "crowd",
        num_envs=2,
        num_agents=100,
        theta_action=True,
        theta_action_range=(1e-3, 1e3),
        max_steps=151,
        safety_radius=scale,
        u_max=2.0 * scale,
        goal_tolerance=0.05 * scale,
        **CROWD,
    )
    env.reset(seed=7)
    rng = np.random.default_rng(7)
    R = env.scenario.params["safety_radius"]
    closest = np.inf
    for _ in range(150):
        _, _, _, _, info = env.step(adversarial(env, rng, strategy))
        closest = min(closest, info["min_distance"].min())
        assert info["min_distance"].min() >= R * (1 - 1e-9)
        assert info["feasible"].all() and not info["cost"].any()
    if strategy == "worst":
        assert closest <= R * (1 + 1e-6)
