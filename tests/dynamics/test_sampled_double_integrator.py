"""The double integrator in discrete time: with the sampled-data row, isolated pairs and random
ramp merges keep their distance at every sample for any gamma and dt the config accepts, and an
agent with one neighbour has a feasible QP whenever h >= 0."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import rsvo_env
from rsvo_env.dynamics import double_integrator_step
from rsvo_env.filter.safety import FilterConfig, SafetyFilter
from tests.support.instances import converging_pair

A_MAX, DS = 5.0, 5.0


def braking_h(p, v, a_max, ds=DS):
    """h = |dp| - Ds - max(0, -q)^2 / (2A) of each pair (rows 2k, 2k + 1), A = 2 a_max."""
    dp, dv = p[0::2] - p[1::2], v[0::2] - v[1::2]
    d = np.linalg.norm(dp, axis=1)
    q = np.einsum("ij,ij->i", dp, dv) / d
    return d - ds - np.maximum(0.0, -q) ** 2 / (4.0 * a_max)


def pairs_heading_in(rng, n_pairs):
    """Pairs heading for a common area from any angle at 2 to 20 m/s, inside the safe set, 100 km
    apart from each other."""
    p, v = np.zeros((2 * n_pairs, 2)), np.zeros((2 * n_pairs, 2))
    k = 0
    while k < n_pairs:
        pk, vk = converging_pair(rng, (8, 60), (2, 20))
        vk += rng.normal(scale=2.0, size=(2, 2))
        if braking_h(pk, vk, A_MAX)[0] >= 0:
            p[2 * k : 2 * k + 2], v[2 * k : 2 * k + 2] = pk + [1e5 * k, 0.0], vk
            k += 1
    return p, v


def pairs_filter(dt, gamma_dt):
    """The filter for pairs 100 km apart: a 10 km neighbour radius makes each pair one
    neighbour to each of its agents (without it a nearly altruistic agent, omega ~ 0, yields to
    far egoists too)."""
    cfg = FilterConfig(
        gamma=gamma_dt / dt,
        safety_radius=DS,
        u_max=A_MAX,
        dt=dt,
        dynamics="double_integrator",
        barrier="braking",
        neighbor_radius=1e4,
    )
    return SafetyFilter(cfg)


@pytest.mark.parametrize("dt", [0.01, 0.1])
@pytest.mark.parametrize("gamma_dt", [0.2, 0.6, 1.0])
def test_isolated_pairs_keep_their_distance_at_any_gamma(dt, gamma_dt):
    """100 pairs, 15 s each: the campaign's failing cases (gamma > 1 at dt = 0.01 and 0.1)."""
    rng = np.random.default_rng(int(1000 * dt + 10 * gamma_dt))
    n_pairs = 100
    p, v = pairs_heading_in(rng, n_pairs)
    goals = -1.5 * (p - np.repeat(p[0::2] * [1, 0], 2, axis=0)) + np.repeat(p[0::2] * [1, 0], 2, 0)
    v_des = rng.uniform(10, 25, (2 * n_pairs, 1))
    theta = rng.uniform(0, 10, 2 * n_pairs)
    flt = pairs_filter(dt, gamma_dt)
    worst, infeasible_in_safe_set = np.inf, 0
    for _ in range(int(round(15.0 / dt))):
        to_goal = goals - p
        nominal = 2.0 * (to_goal / np.linalg.norm(to_goal, axis=1, keepdims=True) * v_des - v)
        nominal *= np.minimum(1.0, A_MAX / np.maximum(np.linalg.norm(nominal, axis=1)[:, None], 1))
        h = braking_h(p, v, A_MAX)
        res = flt.filter(p, nominal, theta, velocities=v)
        stuck = ~res.feasible.reshape(n_pairs, 2).all(axis=1)
        infeasible_in_safe_set += int((stuck & (h >= 0)).sum())
        p, v = double_integrator_step(p, v, res.actions, dt)
        worst = min(worst, float((np.linalg.norm(p[0::2] - p[1::2], axis=1) / DS).min()))
    assert infeasible_in_safe_set == 0
    assert worst >= 1.0 - 1e-9


def merge_h(world, R, a_max):
    dp = world.positions[0] - world.positions[1]
    dv = world.velocities[0] - world.velocities[1]
    d = np.linalg.norm(dp)
    return d - R - max(0.0, -(dp @ dv) / d) ** 2 / (4.0 * a_max)


def random_merge(rng):
    """A merge that starts inside the safe set (h >= 0): from outside it, a collision may be
    physics, not the filter."""
    while True:
        dt, params = draw_merge(rng)
        # the braking barrier's sampled-data row under test (the scenario's default is the
        # stopping-segment barrier)
        env = rsvo_env.parallel_env("ramp_merge", **params, barrier="braking")
        env.reset(seed=0)
        if merge_h(env.unwrapped.world, params["safety_radius"], params["a_max"]) >= 0:
            return env, params


def draw_merge(rng):
    dt = float(rng.choice([0.02, 0.05, 0.1]))
    return dt, {
        "lane_angle_deg": float(rng.uniform(5, 60)),
        "v0": float(rng.uniform(5, 25)),
        "v_des": float(rng.uniform(10, 30)),
        "k_v": float(rng.uniform(0.5, 3)),
        "k_lat": float(rng.uniform(0.5, 3)),
        "a_max": float(rng.uniform(2, 8)),
        "safety_radius": float(rng.uniform(2, 8)),
        "gamma": float(rng.uniform(0.05, 1.0) / dt),
        "dt": dt,
        "theta": rng.uniform(0, 10, 2).tolist(),
    }


@pytest.mark.parametrize("chunk", range(10))
def test_random_ramp_merges_keep_their_distance(chunk):
    """500 random merges (lane angle, speeds, gains, a_max, radius, theta, gamma, dt), 50 a
    chunk: no sample below the safety distance, no infeasible step while h >= 0."""
    rng = np.random.default_rng(7000 + chunk)
    for _ in range(50):
        env, params = random_merge(rng)
        base = env.unwrapped
        R, a_max = params["safety_radius"], params["a_max"]
        while env.agents:
            h = merge_h(base.world, R, a_max)
            _, _, _, _, infos = env.step(base.nominal_actions())
            feasible = all(info["feasible"] for info in infos.values())
            assert feasible or h < 0, (params, h)
            gap = np.linalg.norm(base.world.positions[0] - base.world.positions[1])
            assert gap >= R * (1 - 1e-9), (params, gap)


@settings(max_examples=2000, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.sampled_from([0.01, 0.05, 0.1]),
    st.floats(0.01, 1.0),
    st.floats(0.0, 100.0),
    st.floats(0.0, 100.0),
)
def test_one_neighbour_is_feasible_at_any_gamma(seed, dt, gamma_dt, ti, tj):
    """Any pair state inside the safe set (h >= 0), gamma up to 1 / dt: both QPs are feasible."""
    rng = np.random.default_rng(seed)
    p, v = pairs_heading_in(rng, 1)
    p -= p.mean(axis=0)
    # as close to the boundary h = 0 as the draw allows: shrink the gap
    h = braking_h(p, v, A_MAX)[0]
    dp = p[0] - p[1]
    shrink = rng.uniform(0, 1) * h
    p[0] -= dp / np.linalg.norm(dp) * shrink
    assert braking_h(p, v, A_MAX)[0] >= -1e-9
    cfg = FilterConfig(
        gamma=gamma_dt / dt,
        safety_radius=DS,
        u_max=A_MAX,
        dt=dt,
        dynamics="double_integrator",
        barrier="braking",
    )
    nominal = rng.uniform(-A_MAX, A_MAX, (2, 2))
    res = SafetyFilter(cfg).filter(p, nominal, [ti, tj], velocities=v)
    assert res.feasible.all(), (braking_h(p, v, A_MAX)[0], res.max_violation)


@pytest.mark.parametrize("dt", [0.01, 0.1, 0.2])
@pytest.mark.parametrize("gamma_dt", [0.01, 0.5, 1.0])
@pytest.mark.parametrize("reach", [1e-3, 0.05, 0.4, 0.999])
@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
def test_nearly_head_on_pairs_at_the_boundary_are_feasible(dt, gamma_dt, reach, scale):
    """The window where a tangential speed can be reversed within one step (|w_t| < 2 |U| dt),
    closing fast, h within 1e-4 Ds of 0 (docs/double_integrator.md), across every accepted
    configuration: ``reach`` is dt^2 (a_max + |U|) / Ds, which FilterConfig keeps below 1, at
    1e-3 (the window is tiny) to 0.999 (the edge), gamma dt up to 1, units from millimetres to
    kilometres. Every QP of a pair with h >= 0 is feasible (once 3.2 % were not)."""
    rng = np.random.default_rng(int(100 * dt + 1000 * gamma_dt + 10 * reach))
    n, ds = 1500, 5.0 * scale
    a_max = reach * ds / (dt * dt * (1.0 + np.sqrt(2.0)))
    U, vmax = np.hypot(a_max, a_max), 30.0 * a_max * dt
    z = rng.uniform(0.02, 1.0, n) * vmax
    wt = rng.uniform(0, 2 * U * dt, n) * rng.choice([-1, 1], n)
    gap = ds + z**2 / (4 * a_max) + rng.uniform(0, 1e-4, n) * ds * rng.choice([0, 1], n)
    ang = rng.uniform(0, 2 * np.pi, n)
    radial = np.stack([np.cos(ang), np.sin(ang)], axis=1)
    tangential = np.stack([-radial[:, 1], radial[:, 0]], axis=1)
    spacing = 100 * (ds + vmax**2 / a_max)  # pairs apart: each agent has one neighbour
    centre = np.arange(n)[:, None] * [spacing, 0.0]
    p, v = np.zeros((2 * n, 2)), np.zeros((2 * n, 2))
    p[0::2], p[1::2] = centre + radial * gap[:, None] / 2, centre - radial * gap[:, None] / 2
    w = -z[:, None] * radial + wt[:, None] * tangential
    common = rng.normal(0, vmax / 6, (n, 2))
    v[0::2], v[1::2] = common + w / 2, common - w / 2
    cfg = FilterConfig(
        gamma=gamma_dt / dt,
        safety_radius=ds,
        u_max=a_max,
        dt=dt,
        dynamics="double_integrator",
        barrier="braking",
        neighbor_radius=spacing / 10,
    )
    res = SafetyFilter(cfg).filter(
        p, rng.uniform(-a_max, a_max, (2 * n, 2)), rng.uniform(0, 10, 2 * n), velocities=v
    )
    inside = braking_h(p, v, a_max, ds) >= 0  # round-off puts some a hair outside
    assert inside.sum() > 0.6 * n
    stuck = ~res.feasible.reshape(n, 2).all(axis=1) & inside
    assert stuck.sum() == 0, (stuck.sum(), inside.sum())
