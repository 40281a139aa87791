"""Double integrators of their own size and acceleration limit (``radii=``, ``u_max=`` per
agent): isolated pairs keep ``r_i + r_j`` at every sample from any approach inside the safe set,
in units from millimetres to kilometres; the QP is feasible with one neighbour whenever h >= 0;
the culled filter equals the all-pairs one; equal bodies are the scalar config to the bit; the
sampled-data bound is checked per pair and names it."""

import numpy as np
import pytest

import rsvo_env
from rsvo_env.dynamics import double_integrator_step
from rsvo_env.filter.safety import FilterConfig, SafetyFilter
from rsvo_env.geometry.obstacles import Obstacles
from tests.filter.test_bodies import all_pairs_actions
from tests.support.instances import converging_pair


def pair_h(p, v, radii, a):
    """The braking barrier of each pair (rows 2k, 2k + 1): h = |dp| - Ds - max(0, -q)^2 / (2 A),
    Ds = r_i + r_j, A = a_i + a_j."""
    dp, dv = p[0::2] - p[1::2], v[0::2] - v[1::2]
    d = np.linalg.norm(dp, axis=1)
    q = np.einsum("ij,ij->i", dp, dv) / d
    Ds = radii[0::2] + radii[1::2]
    A = a[0::2] + a[1::2]
    return d - Ds - np.maximum(0.0, -q) ** 2 / (2.0 * A), d / Ds


def heading_in(rng, n_pairs, radii, a, scale):
    """Pairs heading for a common point from any angle, each inside its safe set, 1e5 scale
    apart from each other."""
    p, v = np.zeros((2 * n_pairs, 2)), np.zeros((2 * n_pairs, 2))
    k = 0
    while k < n_pairs:
        pk, vk = converging_pair(rng, (3 * scale, 30 * scale), (0.5 * scale, 6 * scale))
        s = slice(2 * k, 2 * k + 2)
        if pair_h(pk, vk, radii[s], a[s])[0][0] >= 0:
            p[s], v[s] = pk + [1e5 * scale * k, 0.0], vk
            k += 1
    return p, v


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
@pytest.mark.parametrize("dt, gamma_dt", [(0.01, 0.5), (0.05, 1.0), (0.1, 0.3)])
def test_isolated_pairs_of_their_own_size_and_limit_keep_their_distance(scale, dt, gamma_dt):
    rng = np.random.default_rng(int(100 * dt + 10 * gamma_dt + np.log10(scale)))
    n_pairs = 60
    radii = rng.uniform(0.2, 2.0, 2 * n_pairs) * scale
    a = rng.uniform(0.5, 3.0, 2 * n_pairs) * scale
    p, v = heading_in(rng, n_pairs, radii, a, scale)
    goals = p + 3.0 * (np.repeat(p[0::2] * [1, 0], 2, axis=0) - p)
    theta = rng.uniform(0, 10, 2 * n_pairs)
    cfg = FilterConfig(
        gamma=gamma_dt / dt,
        safety_radius=2.0 * scale,
        u_max=3.0 * scale,
        dt=dt,
        dynamics="double_integrator",
        barrier="braking",
        neighbor_radius=1e4 * scale,
    )
    flt = SafetyFilter(cfg)
    worst, infeasible_in_safe_set, touched, steps = np.inf, 0, 0, int(round(12.0 / dt))
    for _ in range(steps):
        to_goal = goals - p
        want = to_goal / np.linalg.norm(to_goal, axis=1, keepdims=True) * 6.0 * scale
        nominal = np.clip(2.0 * (want - v), -a[:, None], a[:, None])
        h, _ = pair_h(p, v, radii, a)
        res = flt.filter(p, nominal, theta, velocities=v, radii=radii, u_max=a)
        assert (np.abs(res.actions) <= a[:, None] * (1 + 1e-12)).all()  # each agent's own box
        stuck = ~res.feasible.reshape(n_pairs, 2).all(axis=1)
        infeasible_in_safe_set += int((stuck & (h >= 0)).sum())
        touched += int((res.intervention > 1e-9 * scale).sum())
        p, v = double_integrator_step(p, v, res.actions, dt)
        worst = min(worst, float(pair_h(p, v, radii, a)[1].min()))
    assert touched > 0  # the filter had work to do
    assert infeasible_in_safe_set == 0
    assert worst >= 1.0 - 1e-9


def crowd(rng, n, scale=1.0):
    side = 3.0 * np.sqrt(n) * scale
    p = rng.uniform(-side, side, (n, 2))
    v = rng.normal(scale=scale, size=(n, 2))
    radii = rng.uniform(0.2, 0.6, n) * scale
    a = rng.uniform(0.5, 3.0, n) * scale
    return p, v, radii, a


@pytest.mark.parametrize("n, seed", [(60, 0), (400, 1)])
def test_culled_equals_all_pairs(n, seed):
    rng = np.random.default_rng(seed)
    p, v, radii, a = crowd(rng, n)
    theta = rng.uniform(0, 10, n)
    dt = 0.05
    flt = SafetyFilter(
        FilterConfig(
            gamma=10.0,
            safety_radius=1.2,
            u_max=3.0,
            dt=dt,
            dynamics="double_integrator",
            barrier="braking",
        )
    )
    goals = rng.uniform(-3 * np.sqrt(n), 3 * np.sqrt(n), (n, 2))
    active = 0
    for _ in range(8):  # a few steps in, so rows bind
        nominal = np.clip(goals - p - v, -a[:, None], a[:, None])
        res = flt.filter(p, nominal, theta, velocities=v, radii=radii, u_max=a)
        ref, _ = all_pairs_actions(flt, p, nominal, theta, radii, a, velocities=v)
        np.testing.assert_allclose(res.actions, ref, rtol=0, atol=1e-12 * 3.0)
        active += int(res.active.sum())
        p, v = double_integrator_step(p, v, res.actions, dt)
    assert active > 0  # rows did bind


def test_equal_bodies_are_the_scalar_config_to_the_bit():
    rng = np.random.default_rng(3)
    p, v, _, _ = crowd(rng, 80)
    nominal = rng.uniform(-2, 2, (80, 2))
    theta = rng.uniform(0, 10, 80)
    flt = SafetyFilter(
        FilterConfig(
            gamma=10.0,
            safety_radius=1.0,
            u_max=2.0,
            dt=0.05,
            dynamics="double_integrator",
            barrier="braking",
        )
    )
    scalar = flt.filter(p, nominal, theta, velocities=v)
    equal = {"radii": np.full(80, 0.5), "u_max": np.full(80, 2.0)}
    own = flt.filter(p, nominal, theta, velocities=v, **equal)
    np.testing.assert_array_equal(scalar.actions, own.actions)
    np.testing.assert_array_equal(scalar.feasible, own.feasible)


def test_a_weaker_brake_is_kept_further_away():
    """Two agents closing at 4 m/s, 3.5 m apart: with a_max 3 each the pair may keep closing
    (h = 1.17); with one agent limited to 0.5 the pair's braking A = a_i + a_j is smaller
    (h = 0.21), so the pair must brake, and the strong agent takes what the weak one cannot."""
    p = np.array([[0.0, 0.0], [3.5, 0.0]])
    v = np.array([[2.0, 0.0], [-2.0, 0.0]])
    flt = SafetyFilter(
        FilterConfig(
            gamma=5.0,
            safety_radius=1.0,
            u_max=3.0,
            dt=0.05,
            dynamics="double_integrator",
            barrier="braking",
        )
    )
    strong = flt.filter(p, np.zeros((2, 2)), np.ones(2), velocities=v, u_max=[3.0, 3.0])
    weak = flt.filter(p, np.zeros((2, 2)), np.ones(2), velocities=v, u_max=[3.0, 0.5])
    assert strong.feasible.all() and weak.feasible.all()
    assert (np.abs(weak.actions) <= [[3.0, 3.0], [0.5, 0.5]]).all()
    np.testing.assert_array_equal(strong.actions, 0.0)
    # the weaker pair brakes: the relative acceleration opens the gap
    assert weak.actions[0, 0] - weak.actions[1, 0] < 0.0
    assert weak.actions[0, 0] < -0.5  # beyond what the weak agent could give


def test_the_sampled_bound_is_checked_per_pair_and_names_it():
    flt = SafetyFilter(
        FilterConfig(
            gamma=5.0,
            safety_radius=1.0,
            u_max=1.0,
            dt=0.1,
            dynamics="double_integrator",
            barrier="braking",
        )
    )
    p = np.array([[0.0, 0.0], [1.0, 0.0], [50.0, 0.0]])
    radii = np.array([0.004, 0.004, 0.5])  # dt^2 (A / 2 + U) = 0.01 (1 + 1.41) > 0.008
    with pytest.raises(ValueError, match=r"agents 0 and 1: dt\^2 \(A / 2 \+ U\)"):
        flt.filter(
            p,
            np.zeros((3, 2)),
            np.ones(3),
            velocities=np.zeros((3, 2)),
            radii=radii,
            u_max=np.ones(3),
        )


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
def test_each_agent_brakes_before_a_circle_with_its_own_limit(scale):
    """Agents of their own size and limit driven straight at a circle from rest to the fastest
    speed each can stop from: no body ever touches it."""
    dt, n = 0.02, 12
    rng = np.random.default_rng(int(np.log10(scale)) + 5)
    a = rng.uniform(0.5, 3.0, n) * scale
    radii = rng.uniform(0.2, 1.0, n) * scale
    rho = 2.0 * scale
    start = 30.0 * scale
    # agent k alone in env k, heading at the circle at the origin of its env
    p = np.zeros((n, 1, 2))
    p[:, 0, 0] = -start
    gap = start - rho - radii
    speed = np.sqrt(2.0 * a * gap) * rng.uniform(0.3, 1.0, n)  # h >= 0 at the start
    v = np.zeros((n, 1, 2))
    v[:, 0, 0] = speed
    flt = SafetyFilter(
        FilterConfig(
            gamma=5.0,
            safety_radius=0.4 * scale,
            u_max=3.0 * scale,
            dt=dt,
            dynamics="double_integrator",
            barrier="braking",
        )
    )
    circle = Obstacles.of(circles=[(0.0, 0.0, rho)])
    closest = np.inf
    for _ in range(int(40 / dt)):
        nominal = np.zeros((n, 1, 2))
        nominal[:, 0, 0] = a  # full throttle at the circle
        res = flt.filter(
            p,
            nominal,
            np.ones((n, 1)),
            velocities=v,
            radii=radii[:, None],
            u_max=a[:, None],
            obstacles=circle,
        )
        assert res.feasible.all()
        p, v = double_integrator_step(p, v, res.actions, dt)
        closest = min(closest, float(((np.linalg.norm(p[:, 0], axis=1) - rho) / radii).min()))
    assert closest >= 1.0 - 1e-9


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
def test_a_custom_pair_of_double_integrators_of_their_own_size_and_limit(scale):
    """The simulator path: ``custom`` with ``dynamics="double_integrator",
                                             barrier="braking"``, per-agent radii and
    a_max, a nearly head-on swap behind the filter: both arrive, bodies never touch."""
    starts = np.array([[-10.0, 0.0], [10.0, 0.3]]) * scale
    env = rsvo_env.parallel_env(
        "custom",
        starts=starts,
        goals=starts[::-1] * [1, 1],
        radii=np.array([0.3, 1.0]) * scale,
        a_max=np.array([0.5, 3.0]) * scale,
        u_max=2.0 * scale,
        safety_radius=1.0 * scale,
        goal_tolerance=0.05 * scale,
        dynamics="double_integrator",
        dt=0.05,
        gamma=5.0,
        max_steps=3000,
        theta=[1.0, 5.0],
    )
    env.reset(seed=0)
    touched = 0
    while env.agents:
        _, _, _, _, infos = env.step(env.unwrapped.nominal_actions())
        touched += sum(i["intervention"] > 0 for i in infos.values())
        assert (np.abs(infos["agent_0"]["u_safe"]) <= 0.5 * scale * (1 + 1e-12)).all()
    m = env.unwrapped.episode_metrics
    assert touched > 0 and m["success"]
    assert m["n_collision_steps"] == 0 and m["n_infeasible"] == 0
    # the episode's closest centre distance against the pair's safe distance r_0 + r_1
    assert m["min_distance"] >= 1.3 * scale * (1 - 1e-9)


def test_custom_dynamics_is_checked():

    kw = {"starts": [[0.0, 0.0], [5.0, 0.0]], "goals": [[5.0, 5.0], [0.0, 5.0]]}
    with pytest.raises(ValueError, match="custom.dynamics = 'hovercraft'"):
        rsvo_env.parallel_env("custom", dynamics="hovercraft", **kw)
    with pytest.raises(TypeError, match="custom.a_max is the double_integrator's parameter"):
        rsvo_env.parallel_env("custom", a_max=2.0, **kw)
    with pytest.raises(ValueError, match=r"custom.a_max\[1\] = -1.0"):
        rsvo_env.parallel_env("custom", dynamics="double_integrator", a_max=[1.0, -1.0], **kw)
    # walls: the backup barrier (the default) takes them; the braking barrier's refusal is in
    # test_backup_barrier
    env = rsvo_env.parallel_env(
        "custom", dynamics="double_integrator", walls=[[[2.0, -5.0], [2.0, -3.0]]], **kw
    )
    assert env.reset(seed=0)[0]
