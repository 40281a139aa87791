"""SafetyFilter on plain arrays: the pair condition, feasibility, culling, bad input."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rsvo_env.dynamics import single_integrator
from rsvo_env.filter.safety import FilterConfig, SafetyFilter
from rsvo_env.geometry import pairs


def spaced_positions(rng, n, radius, spacing=1.05, side=None):
    side = side or 2.5 * np.sqrt(n) * radius
    pts = []
    while len(pts) < n:
        p = rng.uniform(-side / 2, side / 2, 2)
        if all(np.linalg.norm(p - q) >= spacing * radius for q in pts):
            pts.append(p)
    return np.array(pts)


def random_theta(rng, n):
    theta = 10.0 ** rng.uniform(-3, 3, n)
    theta[rng.random(n) < 0.2] = 0.0
    return theta


@settings(max_examples=150, deadline=None)
@given(st.integers(2, 12), st.integers(0, 2**32 - 1), st.sampled_from(["asymmetric", "symmetric"]))
def test_pairs_satisfy_centralized_condition(n, seed, weighting):
    """Thm. 1: the two filtered actions of every pair satisfy eq. centralized-cbf."""
    rng = np.random.default_rng(seed)
    R, gamma = rng.uniform(0.3, 2.0), rng.uniform(0.5, 50.0)
    x = spaced_positions(rng, n, R, spacing=rng.uniform(1.0, 1.5))
    nominal = rng.uniform(-3, 3, (n, 2))
    theta = random_theta(rng, n)
    f = SafetyFilter(FilterConfig(gamma=gamma, safety_radius=R, u_max=3.0, weighting=weighting))
    res = f.filter(x, nominal, theta)
    assert res.feasible.all()
    u = res.actions
    i, j = np.triu_indices(n, 1)
    dx = x[i] - x[j]
    h = np.sum(dx * dx, axis=1) - R**2
    lhs = 2 * np.sum(dx * (u[i] - u[j]), axis=1) + gamma * h
    assert np.all(lhs >= -1e-9 * (1 + gamma * np.abs(h)))
    assert np.all(np.abs(u) <= 3.0)


@settings(max_examples=150, deadline=None)
@given(st.integers(2, 15), st.integers(0, 2**32 - 1))
def test_zero_is_feasible_in_the_safe_set(n, seed):
    rng = np.random.default_rng(seed)
    x = spaced_positions(rng, n, 1.0, spacing=1.0)
    theta = random_theta(rng, n)
    f = SafetyFilter(FilterConfig(gamma=5.0, safety_radius=1.0, u_max=2.0))
    res = f.filter(x, rng.normal(size=(n, 2)), theta)
    rows = res.rows
    # u = 0 satisfies every row (b >= 0) whenever all h >= 0
    assert res.min_h >= 0
    assert np.all(rows.b[rows.mask] >= 0)
    assert res.feasible.all()


@settings(max_examples=60, deadline=None)
@given(st.integers(2, 40), st.integers(0, 2**32 - 1))
def test_culling_changes_no_solution(n, seed):
    rng = np.random.default_rng(seed)
    x = spaced_positions(rng, n, 1.0, spacing=1.0, side=4 * np.sqrt(n))
    theta = rng.uniform(0.5, 10, n)
    nominal = rng.uniform(-2, 2, (n, 2))
    cfg = FilterConfig(gamma=10.0, safety_radius=1.0, u_max=2.0)
    res = SafetyFilter(cfg).filter(x, nominal, theta)
    I, J = pairs.candidate_pairs(x[None])
    w = SafetyFilter(cfg).pair_weights(theta, None, I, J)
    full = single_integrator.single_integrator_rows(
        x, w, I, J, 10.0, 1.0, cfg.lo, cfg.hi, cull=False
    )
    from rsvo_env.qp import exact

    u_full, feasible, _, _ = exact.solve_batch(nominal, full.A, full.b, full.mask, cfg.lo, cfg.hi)
    np.testing.assert_allclose(res.actions, u_full, atol=1e-12)
    assert full.mask.sum() >= res.rows.mask.sum()


def test_kdtree_pairs_match_dense_pairs():
    rng = np.random.default_rng(0)
    n = 400
    x = spaced_positions(rng, n, 1.0, spacing=1.0)
    theta = rng.uniform(1, 5, n)
    nominal = rng.uniform(-2, 2, (n, 2))
    cfg = FilterConfig(gamma=10.0, safety_radius=1.0, u_max=2.0)
    flt = SafetyFilter(cfg)
    res = flt.filter(x, nominal, theta)
    I, J = np.triu_indices(n, 1)
    w = flt.pair_weights(theta, None, I, J)
    dense = single_integrator.single_integrator_rows(x, w, I, J, 10.0, 1.0, cfg.lo, cfg.hi)
    from rsvo_env.qp import exact

    u_dense = exact.solve_batch(nominal, dense.A, dense.b, dense.mask, cfg.lo, cfg.hi)[0]
    np.testing.assert_allclose(res.actions, u_dense, atol=1e-12)
    assert res.min_h == pytest.approx(dense.pair_h.min())
    radius = flt.pair_radius(theta, None)
    assert np.isfinite(radius)


def test_small_neighbor_radius_warns():
    cfg = FilterConfig(gamma=10.0, safety_radius=1.0, u_max=2.0, neighbor_radius=1.5)
    x = np.array([[0.0, 0.0], [3.0, 0.0]])
    with pytest.warns(UserWarning, match="sensing radius"):
        SafetyFilter(cfg).filter(x, np.zeros((2, 2)), [1.0, 1.0])


def test_egoist_keeps_more_freedom():
    x = np.array([[-2.0, 0.0], [2.0, 0.0]])
    nominal = np.array([[3.0, 0.0], [-3.0, 0.0]])
    f = SafetyFilter(FilterConfig(gamma=1.0, safety_radius=1.0, u_max=3.0))
    res = f.filter(x, nominal, [1.0, 4.0])
    assert res.actions[0, 0] > -res.actions[1, 0] > 0  # the egoist (agent 0) moves faster
    sym = SafetyFilter(FilterConfig(gamma=1.0, safety_radius=1.0, u_max=3.0, weighting="symmetric"))
    r2 = sym.filter(x, nominal, [1.0, 4.0])
    assert r2.actions[0, 0] == pytest.approx(-r2.actions[1, 0], abs=1e-15)
    assert res.intervention[0] < res.intervention[1]


def test_reference_backend_matches_exact():
    rng = np.random.default_rng(5)
    x = spaced_positions(rng, 10, 1.0)
    nominal = rng.uniform(-3, 3, (10, 2))
    theta = rng.uniform(0, 5, 10)
    a = SafetyFilter(FilterConfig(gamma=8.0, u_max=3.0)).filter(x, nominal, theta)
    b = SafetyFilter(FilterConfig(gamma=8.0, u_max=3.0, solver="daqp")).filter(x, nominal, theta)
    np.testing.assert_allclose(a.actions, b.actions, atol=1e-8)
    np.testing.assert_array_equal(a.active, b.active)


# ---- bad input: the exception names the field, the agent and the value ----

GOOD = dict(
    positions=np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 3.0]]),
    nominal=np.zeros((3, 2)),
    theta=np.array([1.0, 2.0, 3.0]),
)


@pytest.mark.parametrize(
    "field,value,pattern",
    [
        ("positions", [[0, 0], [3, 0], [np.nan, 3]], r"positions\[2\] = \[nan, 3.0\].*agent 2"),
        ("nominal", [[0, 0], [np.inf, 0], [0, 0]], r"nominal\[1\] = \[inf, 0.0\].*agent 1"),
        ("nominal", np.zeros((3, 3)), r"nominal has shape \(3, 3\), expected \(3, 2\)"),
        ("nominal", np.zeros((2, 2)), r"nominal has shape \(2, 2\), expected \(3, 2\)"),
        ("theta", [1.0, -0.5, 2.0], r"theta\[1\] = -0.5.*agent 1"),
        ("theta", [1.0, 2.0, np.nan], r"theta\[2\] = nan.*agent 2"),
        ("theta", [1.0, 2.0], r"theta has 2 entries, expected 3"),
    ],
)
def test_bad_filter_input(field, value, pattern):
    args = {**GOOD, field: np.asarray(value, dtype=float)}
    with pytest.raises(ValueError, match=pattern):
        SafetyFilter(FilterConfig()).filter(**args)


def test_double_integrator_needs_velocities():
    f = SafetyFilter(FilterConfig(dynamics="double_integrator", u_max=5.0, gamma=1.0))
    with pytest.raises(ValueError, match="velocities"):
        f.filter(**GOOD)
    with pytest.raises(ValueError, match=r"velocities\[0\] = \[nan, 0.0\].*agent 0"):
        f.filter(**GOOD, velocities=[[np.nan, 0], [0, 0], [0, 0]])


@pytest.mark.parametrize(
    "kwargs,pattern",
    [
        ({"gamma": 0.0}, r"gamma = 0.0"),
        ({"gamma": -1.0}, r"gamma = -1.0"),
        ({"gamma": np.nan}, r"gamma = nan"),
        ({"gamma": 200.0, "dt": 0.01}, r"gamma \* dt = 200.0 \* 0.01"),
        ({"safety_radius": 0.0}, r"safety_radius = 0.0"),
        ({"safety_radius": -2.0}, r"safety_radius = -2.0"),
        ({"u_max": 1.0, "u_min": 1.0}, r"u_min = \[1.0, 1.0\], u_max = \[1.0, 1.0\]"),
        ({"u_max": np.inf}, r"u_max = \[inf, inf\]"),
        ({"dynamics": "bicycle"}, r"dynamics = 'bicycle'"),
        ({"weighting": "selfish"}, r"weighting = 'selfish'"),
        ({"split": "half"}, r"split = 'half'"),
        ({"barrier": "exp"}, r"barrier = 'exp'"),
        ({"solver": "nope"}, r"solver = 'nope'"),
        ({"dt": 0.0}, r"dt = 0.0"),
        ({"neighbor_radius": -1.0}, r"neighbor_radius = -1.0"),
    ],
)
def test_bad_config(kwargs, pattern):
    with pytest.raises(ValueError, match=pattern):
        FilterConfig(**kwargs)


def test_bad_omega_matrix():
    bad = np.array([[0, 0.4, 0.5], [0.4, 0, 0.5], [0.5, 0.5, 0]])
    with pytest.raises(ValueError, match=r"omega\[0, 1\] \+ omega\[1, 0\] = 1"):
        SafetyFilter(FilterConfig()).filter(**GOOD, omega=bad)


@pytest.mark.parametrize("batched", [False, True])
def test_rows_of_the_compiled_pass_are_built_when_asked_for(batched):
    """The compiled all-pairs pass keeps no rows; ``res.rows`` builds them on first access, the
    general path's rows of the inputs as they were (the caller's arrays may change since)."""
    rng = np.random.default_rng(3)
    n = 100
    x = spaced_positions(rng, n, 1.0, spacing=1.05)
    nominal, theta = rng.uniform(-2, 2, (n, 2)), rng.uniform(1, 10, n)
    flt = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=1.0, u_max=2.0))
    args = (x[None], nominal[None], theta[None]) if batched else (x, nominal, theta)
    res = flt.filter(*args)
    assert res.kept_rows is None and res.rows_later is not None  # the compiled pass ran
    want = flt.apply(x[None], nominal[None], theta[None], with_rows=True)
    x += 100.0  # the caller moves on
    rows = res.rows
    assert res.rows is rows and res.rows_later is None  # built once
    np.testing.assert_array_equal(rows.flat_A, want.rows.flat_A)
    np.testing.assert_array_equal(rows.flat_b, want.rows.flat_b)
    np.testing.assert_array_equal(rows.offsets, want.rows.offsets)
    np.testing.assert_array_equal(res.actions.reshape(-1, 2), want.actions.reshape(-1, 2))
    assert rows.n_pairs == want.rows.n_pairs > 0
