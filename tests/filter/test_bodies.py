"""Agents with their own size and limits (``radii``, ``u_max`` per agent): heterogeneous
single-integrator crowds stay safe at ``r_i + r_j``, every QP feasible while the state is safe,
the culled filter equal to the all-pairs one, the compiled dense pass equal to the general one,
and the reference solver in agreement, in any units."""

import numpy as np
import pytest

from rsvo_env.filter.safety import FilterConfig, SafetyFilter
from rsvo_env.geometry import pairs
from rsvo_env.geometry.bodies import Bodies
from rsvo_env.qp import solve as solvers
from rsvo_env.util import sizes


def scene(n: int, seed: int, scale: float = 1.0):
    """n bodies of radius 0.2-2 on a jittered grid (no overlap), goals a shuffle of the starts
    (crossing traffic), theta in [0, 10] with some exact zeros, u_max in [0.5, 3]."""
    rng = np.random.default_rng(seed)
    radii = rng.uniform(0.2, 2.0, n)
    side = int(np.ceil(np.sqrt(n)))
    cell = 2 * 2.0 + 0.5
    grid = np.stack(np.meshgrid(np.arange(side), np.arange(side)), -1).reshape(-1, 2)[:n]
    x = (grid + rng.uniform(-0.05, 0.05, (n, 2))) * cell
    theta = rng.uniform(0.0, 10.0, n)
    theta[rng.choice(n, max(1, n // 20), replace=False)] = 0.0
    u_max = rng.uniform(0.5, 3.0, n)
    goals = x[rng.permutation(n)]
    return x * scale, goals * scale, theta, radii * scale, u_max * scale


def nominal_to(goals, x, u_max):
    d = goals - x
    dist = np.linalg.norm(d, axis=1, keepdims=True)
    return d / np.maximum(dist, 1e-300) * np.minimum(dist, u_max[:, None])


def all_pairs_actions(flt, x, nominal, theta, radii, u_max, velocities=None):
    """The filter with every pair examined and no culling radius: the definition."""
    cfg, n = flt.config, len(x)
    bodies = Bodies.of(cfg, 1, n, radii[None], u_max[None])
    I, J = pairs.all_pairs(n)
    w = flt.pair_weights(theta, None, I, J)
    rows = cfg.model.rows(cfg, x, velocities, w, I, J, bodies)
    out = solvers.solve(
        "exact", nominal, rows.flat_A, rows.flat_b, rows.offsets, bodies.lo, bodies.hi
    )
    return out[0], out[1]


def gaps(x, radii):
    """Every pair's distance over its safe distance ``r_i + r_j``: the smallest."""
    I, J = pairs.all_pairs(len(x))
    return float((np.linalg.norm(x[I] - x[J], axis=1) / (radii[I] + radii[J])).min())


@pytest.mark.parametrize(
    "n,steps,scale",
    [(50, 120, 1e-3), (50, 120, 1e3), (400, 60, 1e-3), (400, 60, 1.0), (400, 60, 1e3),
     (2000, 25, 1.0)],
)  # fmt: skip
@pytest.mark.parametrize("gamma", [10.0, 20.0])  # gamma dt = 0.5 and the edge, 1
def test_heterogeneous_crowd_keeps_every_pair_apart(n, steps, scale, gamma):
    dt = 0.05
    x, goals, theta, radii, u_max = scene(n, n, scale)
    flt = SafetyFilter(FilterConfig(gamma=gamma, safety_radius=scale, u_max=3.0 * scale, dt=dt))
    worst = np.inf
    for _ in range(steps):
        res = flt.filter(x, nominal_to(goals, x, u_max), theta, radii=radii, u_max=u_max)
        assert res.feasible.all(), "a QP was infeasible while the state was safe"
        assert (np.abs(res.actions) <= u_max[:, None]).all()
        x = x + dt * res.actions
        worst = min(worst, gaps(x, radii))
    assert worst >= 1.0 - 1e-9
    # and the crowd truly interacted: some pair came close to touching
    assert worst < 1.2


@pytest.mark.parametrize("n,seed", [(1100, 0), (2000, 1)])
def test_culled_equals_all_pairs(n, seed):
    dt = 0.05
    x, goals, theta, radii, u_max = scene(n, seed)
    flt = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=1.0, u_max=3.0, dt=dt))
    for _ in range(8):  # a few steps in, so rows bind
        nominal = nominal_to(goals, x, u_max)
        res = flt.filter(x, nominal, theta, radii=radii, u_max=u_max)
        ref, feasible = all_pairs_actions(flt, x, nominal, theta, radii, u_max)
        np.testing.assert_allclose(res.actions, ref, rtol=0, atol=1e-12 * 3.0)
        assert feasible.all() and res.active.sum() > 0
        x = x + dt * res.actions


@pytest.mark.parametrize("n", [60, 100, sizes.COMPILED_FILTER_MAX_AGENTS])
def test_compiled_dense_pass_equals_the_general_path(n):
    """Up to the dense kernel's size, on both sides of the size where the general path stops
    examining every pair and searches a grid per agent."""
    x, goals, theta, radii, u_max = scene(n, 5)
    flt = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=1.0, u_max=3.0, dt=0.05))
    for _ in range(20):
        nominal = nominal_to(goals, x, u_max)
        bodies = Bodies.of(flt.config, 1, n, radii[None], u_max[None])
        fast = flt.apply(x[None], nominal[None], theta[None], bodies=bodies)
        slow = flt.apply(x[None], nominal[None], theta[None], bodies=bodies, with_rows=True)
        assert fast.rows is None and slow.rows is not None
        np.testing.assert_array_equal(fast.actions, slow.actions)
        np.testing.assert_array_equal(fast.n_rows, slow.n_rows)
        np.testing.assert_array_equal(fast.min_h, slow.min_h)
        x = x + 0.05 * fast.actions[0]


def test_reference_solver_agrees():
    x, goals, theta, radii, u_max = scene(40, 9)
    exact = SafetyFilter(FilterConfig(gamma=10.0, u_max=3.0, dt=0.05))
    ref = SafetyFilter(FilterConfig(gamma=10.0, u_max=3.0, dt=0.05, solver="clarabel"))
    for _ in range(15):
        nominal = nominal_to(goals, x, u_max)
        a = exact.filter(x, nominal, theta, radii=radii, u_max=u_max)
        b = ref.filter(x, nominal, theta, radii=radii, u_max=u_max)
        np.testing.assert_allclose(a.actions, b.actions, atol=1e-6 * 3.0)
        x = x + 0.05 * a.actions


def test_equal_bodies_are_the_scalar_safety_radius_to_the_bit():
    x, goals, theta, _, _ = scene(80, 3)
    flt = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=1.7, u_max=2.0, dt=0.05))
    nominal = nominal_to(goals, x, np.full(80, 2.0))
    a = flt.filter(x, nominal, theta)
    b = flt.filter(x, nominal, theta, radii=np.full(80, 1.7 / 2), u_max=np.full(80, 2.0))
    np.testing.assert_array_equal(a.actions, b.actions)
    assert b.min_h == pytest.approx(a.min_h, rel=1e-12)


def test_a_smaller_body_may_come_closer():
    """Two agents meeting head on stop at the sum of their radii, not at safety_radius."""
    x = np.array([[0.0, 0.0], [3.0, 0.0]])
    flt = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=2.0, u_max=1.0, dt=0.05))
    radii = np.array([0.3, 0.2])
    for _ in range(400):
        nominal = np.array([[1.0, 0.0], [-1.0, 0.0]])
        x = x + 0.05 * flt.filter(x, nominal, np.ones(2), radii=radii).actions
    d = float(np.linalg.norm(x[0] - x[1]))
    assert 0.5 * (1 - 1e-9) <= d < 0.51


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"radii": np.r_[0.5, -1.0, 0.5]}, r"radii\[1\] = -1.0 .*agent 1"),
        ({"radii": np.r_[0.5, np.nan, 0.5]}, r"radii\[1\] = nan .*agent 1"),
        ({"radii": np.r_[0.5, 0.0, 0.5]}, r"radii\[1\] = 0.0"),
        ({"radii": np.ones(2)}, r"radii has shape \(2,\), expected \(3,\)"),
        ({"radii": ["a", "b", "c"]}, r"radii must be real numbers"),
        ({"radii": [True, True, True]}, r"radii must be real numbers"),
        ({"u_max": np.r_[1.0, 1.0, np.inf]}, r"u_max\[2\] = inf .*agent 2"),
        ({"u_max": np.r_[1.0, 1.0, 1j]}, r"u_max must be real numbers"),
    ],
)
def test_bad_bodies_are_refused_by_name(kwargs, match):
    flt = SafetyFilter(FilterConfig())
    x = np.array([[0.0, 0.0], [5.0, 0.0], [10.0, 0.0]])
    with pytest.raises(ValueError, match=match):
        flt.filter(x, np.zeros((3, 2)), np.ones(3), **kwargs)


def test_per_agent_bodies_refused_where_not_supported():
    x = np.array([[0.0, 0.0], [5.0, 0.0]])
    with pytest.raises(ValueError, match="u_min"):
        SafetyFilter(FilterConfig(u_min=-1.0)).filter(
            x, np.zeros((2, 2)), np.ones(2), u_max=np.ones(2)
        )
    uni = SafetyFilter(FilterConfig(dynamics="unicycle", u_max=2.0, lookahead=0.2, w_max=1.0))
    with pytest.raises(ValueError, match=r"u_max\[1\] = 0.1 must be above lookahead \* w_max"):
        uni.filter(x, np.zeros((2, 2)), np.ones(2), headings=np.zeros(2), u_max=[1.0, 0.1])


def test_batched_bodies_name_the_env():
    flt = SafetyFilter(FilterConfig())
    x = np.zeros((2, 2, 2))
    x[:, 1, 0] = 5.0
    radii = np.ones((2, 2))
    radii[1, 0] = -2.0
    with pytest.raises(ValueError, match=r"radii\[1\]\[0\] = -2.0 .*env 1, agent 0"):
        flt.filter(x, np.zeros((2, 2, 2)), np.ones((2, 2)), radii=radii)
