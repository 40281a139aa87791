"""Per-agent exact culling (single integrator): each agent examines the neighbours within its own
radius, so a few altruists or a theta = 0 agent no longer make every agent examine every pair,
and the actions are those of the all-pairs filter."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rsvo_env.dynamics import single_integrator
from rsvo_env.dynamics.barriers import pair_rows
from rsvo_env.filter.safety import FilterConfig, SafetyFilter
from rsvo_env.geometry import pairs
from rsvo_env.qp import exact
from rsvo_env.responsibility.svo import pair_omega
from rsvo_env.scenarios import Crowd
from rsvo_env.util import grid


def crowd(n, seed):
    return Crowd(num_agents=n, spacing_factor=1.0)._spread(np.random.default_rng(seed))


def moving(n, seed, u_max=2.0):
    """Nominal actions at full speed in random directions: every agent going somewhere (at
    rest, the filter examines nothing beyond the safe distance, rsvo_env.filter.projection_disk)."""
    angle = np.random.default_rng(seed).uniform(0.0, 2.0 * np.pi, n)
    return u_max * np.stack([np.cos(angle), np.sin(angle)], axis=-1)


def all_pairs_actions(flt, x, nominal, theta):
    cfg = flt.config
    I, J = pairs.all_pairs(len(x))
    w = flt.pair_weights(theta, None, I, J)
    rows = single_integrator.single_integrator_rows(
        x, w, I, J, cfg.gamma, cfg.safety_radius, cfg.lo, cfg.hi
    )
    return exact.solve_batch(nominal, rows.A, rows.b, rows.mask, cfg.lo, cfg.hi)[0]


@pytest.mark.parametrize("n,seed", [(50, 0), (300, 1), (1000, 2), (2000, 3)])
def test_culled_equals_all_pairs(n, seed):
    rng = np.random.default_rng(seed)
    x = crowd(n, seed)
    theta = 10.0 ** rng.uniform(0, 2, n)  # ratios up to 100
    theta[rng.choice(n, 3, replace=False)] = 0.0
    nominal = -2.0 * x / np.maximum(np.linalg.norm(x, axis=1, keepdims=True), 1e-9)  # inward
    flt = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=1.0, u_max=2.0, dt=0.01))
    res = flt.filter(x, nominal, theta)
    np.testing.assert_allclose(res.actions, all_pairs_actions(flt, x, nominal, theta), atol=1e-12)


def pairs_examined(theta, x):
    flt = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=1.0, u_max=2.0, dt=0.01))
    return flt.filter(x, moving(len(x), 0), theta).rows.n_pairs


def global_radius_pairs(theta, x):
    """What one radius for every agent (from the smallest weight of all) examines."""
    flt = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=1.0, u_max=2.0, dt=0.01))
    return len(pairs.candidate_pairs(x[None], flt.pair_radius(theta, None))[0])


def test_personalities_do_not_blow_up_the_pair_search():
    n = 2000
    x = crowd(n, 7)
    equal = pairs_examined(np.ones(n), x)
    # one theta = 0 agent: every pair before (infinite radius); now at most its own N - 1 rows
    one_zero = np.r_[0.0, np.ones(n - 1)]
    assert global_radius_pairs(one_zero, x) == n * (n - 1) // 2
    assert pairs_examined(one_zero, x) <= equal + (n - 1)
    # theta spread over 1..10: an altruist facing an egoist (omega ~ 0.02) can truly be bound
    # ~28 m away, but only the altruists search that far, and only for the egoists
    spread = np.random.default_rng(7).uniform(1, 10, n)
    examined = pairs_examined(spread, x)
    assert examined <= 0.1 * global_radius_pairs(spread, x)
    # No exact culling that looks at the state alone can examine fewer pairs than those with a
    # row that binds somewhere in the box; the search stays within 2x of that floor.
    assert examined <= 2.0 * pairs_that_can_bind(spread, x)
    assert pairs_that_can_bind(spread, x) > 3 * pairs_that_can_bind(np.ones(n), x)


def pairs_that_can_bind(theta, x):
    """Pairs (of all) with a row that binds for some action in the box, at these positions."""
    I, J = pairs.all_pairs(len(x))
    d = x[I] - x[J]
    h = (d**2).sum(axis=1) - 1.0
    w = pair_omega(theta[I], theta[J])
    return int((np.minimum(w, 1 - w) * 10.0 * h < 2 * 2.0 * np.abs(d).sum(axis=1)).sum())


def brute_pairs(x, radius, group):
    """Pairs (flat, sorted) closer than the larger of their radii against each other's group;
    a radius of 0 searches nothing."""
    E, n = x.shape[:2]
    out = []
    for e in range(E):
        for i in range(n):
            for j in range(i + 1, n):
                d2 = ((x[e, i] - x[e, j]) ** 2).sum()
                r = (radius[e, i, group[e, j]], radius[e, j, group[e, i]])
                if any(ri > 0 and d2 <= np.float64(ri) * ri for ri in r):
                    out.append((e * n + i, e * n + j))
    return np.array(out, dtype=np.int64).reshape(-1, 2)


@pytest.mark.parametrize("seed", range(12))
def test_grid_search_equals_brute_force(seed):
    """Each pair is kept by one scan (the larger radius, the lower index on a tie; a group
    skipped by an agent whose every pair there a member keeps): ties of radii included."""
    rng = np.random.default_rng(seed)
    E, n, K = int(rng.integers(1, 4)), int(rng.integers(2, 90)), int(rng.integers(1, 4))
    scale = 10.0 ** rng.uniform(-3, 3)
    x = rng.uniform(-1, 1, (E, n, 2)) * scale
    x[:, 1] = x[:, 0]  # coincident agents
    if seed % 2:
        x[..., 1] = 0.0  # all on a line: a degenerate box
    if seed % 3:
        radius = rng.uniform(0, 0.6, (E, n, K)) * scale
    else:  # few distinct radii: many pairs whose two radii are equal
        radius = rng.choice([0.15, 0.3, 0.6], (E, n, K)) * scale
    radius[rng.uniform(size=(E, n, K)) < 0.2] = 0.0
    radius[0, 0, 0] = 1e300  # one agent that searches everywhere
    group = rng.integers(0, K, (E, n))
    I, J = grid.pairs_within_radii(x, radius, group)
    with np.errstate(over="ignore"):
        np.testing.assert_array_equal(np.stack([I, J], axis=1), brute_pairs(x, radius, group))
    d = np.linalg.norm(x[:, :, None] - x[:, None], axis=-1) + np.where(np.eye(n), np.inf, 0)
    np.testing.assert_array_equal(grid.nearest_distance(x), d.min(axis=-1))


@pytest.mark.parametrize("K", [1, 2, 3])
def test_grid_search_with_every_radius_equal(K):
    """Every radius the same: every pair a tie, which the lower index keeps; no agent may skip
    a group whose radii merely equal its own."""
    side = np.arange(6, dtype=float)
    x = np.stack(np.meshgrid(side, side), -1).reshape(1, -1, 2)
    n = x.shape[1]
    radius = np.full((1, n, K), 1.5)
    group = (np.arange(n) % K)[None].astype(np.int64)
    I, J = grid.pairs_within_radii(x, radius, group)
    np.testing.assert_array_equal(np.stack([I, J], axis=1), brute_pairs(x, radius, group))


def all_pairs_double_integrator(flt, x, v, nominal, theta):
    cfg = flt.config
    I, J = pairs.all_pairs(len(x))
    w = flt.pair_weights(theta, None, I, J)
    rows = pair_rows.double_integrator_rows(
        x,
        v,
        w,
        I,
        J,
        pair_rows.BarrierSpec(
            cfg.gamma,
            cfg.safety_radius,
            cfg.lo,
            cfg.hi,
            cfg.barrier,
            cfg.split,
            cfg.gamma2,
            cfg.dt,
        ),
    )
    return exact.solve_batch(nominal, rows.A, rows.b, rows.mask, cfg.lo, cfg.hi)


@pytest.mark.parametrize(
    "n,seed,barrier,dt",
    [
        (100, 0, "braking", None),
        (300, 1, "braking", 0.05),
        (1000, 2, "hocbf", None),
        (2000, 3, "braking", 0.01),
    ],
)
def test_double_integrator_culled_equals_all_pairs(n, seed, barrier, dt):
    """No user radius: each agent's radius from the closing speeds and the acceleration box."""
    rng = np.random.default_rng(seed)
    x = crowd(n, seed) * 2.0
    v = rng.normal(0, 1.0, (n, 2))
    theta = 10.0 ** rng.uniform(0, 2, n)
    theta[rng.choice(n, 3, replace=False)] = 0.0
    nominal = rng.uniform(-1, 1, (n, 2))
    cfg = FilterConfig(
        gamma=1.0,
        safety_radius=1.0,
        u_max=1.0,
        dt=dt,
        dynamics="double_integrator",
        barrier=barrier,
    )
    flt = SafetyFilter(cfg)
    res = flt.filter(x, nominal, theta, velocities=v)
    ref, feasible = all_pairs_double_integrator(flt, x, v, nominal, theta)[:2]
    np.testing.assert_allclose(res.actions, ref, atol=1e-12)
    np.testing.assert_array_equal(res.feasible, feasible)


def test_double_integrator_crowd_examines_few_pairs():
    n = 2000
    rng = np.random.default_rng(0)
    x = Crowd(num_agents=n)._spread(rng)
    v = rng.normal(0, 0.5, (n, 2))
    cfg = FilterConfig(gamma=1.0, u_max=1.0, dt=0.05, dynamics="double_integrator")
    examined = SafetyFilter(cfg).filter(x, np.zeros((n, 2)), np.ones(n), velocities=v).rows.n_pairs
    assert examined < 0.05 * n * (n - 1) / 2


def swapped_weights(theta):
    """A callable weighting: the R-SVO weights with the roles of egoist and altruist swapped."""
    from rsvo_env.responsibility.svo import weight_matrix

    w = 1.0 - weight_matrix(theta)
    np.fill_diagonal(w, 0.0)
    return w


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 2**31),
    scale=st.sampled_from([1e-3, 1.0, 1e3]),
    kind=st.sampled_from(["single", "braking", "braking_dt", "hocbf"]),
    weighting=st.sampled_from(["asymmetric", "symmetric", "callable"]),
)
def test_culled_equals_all_pairs_in_any_units(seed, scale, kind, weighting):
    """Random crowds beyond the dense size, in millimetres to kilometres: the culled filter's
    actions and flags are the all-pairs filter's."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(65, 160))
    x = crowd(n, seed % 1000) * scale
    theta = 10.0 ** rng.uniform(0, 2, n)
    theta[rng.uniform(size=n) < 0.03] = 0.0
    u = 2.0 * scale
    nominal = rng.uniform(-u, u, (n, 2))
    mode = swapped_weights if weighting == "callable" else weighting
    dyn = "single_integrator" if kind == "single" else "double_integrator"
    cfg = FilterConfig(
        gamma=float(rng.uniform(0.5, 10.0)),
        safety_radius=scale,
        u_max=u,
        dt=0.05 if kind in ("single", "braking_dt") else None,
        dynamics=dyn,
        barrier="hocbf" if kind == "hocbf" else "braking",
        weighting=mode,
    )
    flt = SafetyFilter(cfg)
    v = rng.normal(0, scale, (n, 2)) if dyn != "single_integrator" else None
    res = flt.filter(x, nominal, theta, velocities=v)
    I, J = pairs.all_pairs(n)
    w = flt.pair_weights(theta, None, I, J)
    if v is None:
        rows = single_integrator.single_integrator_rows(
            x, w, I, J, cfg.gamma, scale, cfg.lo, cfg.hi
        )
    else:
        rows = pair_rows.double_integrator_rows(
            x,
            v,
            w,
            I,
            J,
            pair_rows.BarrierSpec(cfg.gamma, scale, cfg.lo, cfg.hi, cfg.barrier, dt=cfg.dt),
        )
    ref, feasible = exact.solve_batch(nominal, rows.A, rows.b, rows.mask, cfg.lo, cfg.hi)[:2]
    np.testing.assert_array_equal(res.feasible, feasible)
    np.testing.assert_allclose(res.actions, ref, atol=1e-12 * u)
