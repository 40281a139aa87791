"""Double integrator: the split, one-neighbour feasibility, and sampled-data safety of pairs."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rsvo_env.dynamics import double_integrator_step
from rsvo_env.dynamics.barriers import pair_rows
from rsvo_env.filter.safety import FilterConfig, SafetyFilter

A_MAX, DS = 5.0, 5.0
LO, HI = np.full(2, -A_MAX), np.full(2, A_MAX)


def braking_h(p, v, a_max=A_MAX, ds=DS):
    dp, dv = p[0] - p[1], v[0] - v[1]
    d = np.linalg.norm(dp)
    q = dp @ dv / d
    return d - ds - max(0.0, -q) ** 2 / (4 * a_max)


def pair_state(rng, safe=True):
    """Two vehicles heading for a common area from any angle, started inside the safe set."""
    while True:
        ang = rng.uniform(0, 2 * np.pi)
        ang2 = ang + rng.uniform(-np.pi, np.pi)
        d1, d2 = rng.uniform(8, 60, 2)
        p = np.array([[np.cos(ang), np.sin(ang)], [np.cos(ang2), np.sin(ang2)]]) * [[d1], [d2]]
        v = -p / np.linalg.norm(p, axis=1, keepdims=True) * rng.uniform(2, 20, (2, 1))
        v += rng.normal(scale=2.0, size=(2, 2))
        if not safe or braking_h(p, v) >= 0:
            return p, v


def rhs_reference(p, v, barrier, gamma, gamma2=None):
    dp, dv = p[0] - p[1], v[0] - v[1]
    d = np.linalg.norm(dp)
    if barrier == "braking":
        A = 2 * A_MAX
        q = dp @ dv / d
        h = d - DS - max(0.0, -q) ** 2 / (2 * A)
        return (dv @ dv - q * q) - A * d + gamma * h * A * d / (-q), q < 0
    g2 = gamma if gamma2 is None else gamma2
    return 2 * dv @ dv + 2 * (gamma + g2) * dp @ dv + gamma * g2 * (d * d - DS**2), True


@settings(max_examples=300, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.sampled_from(["capability", "sign_aware", "paper"]),
    st.sampled_from(["braking", "hocbf"]),
    st.floats(0.0, 20.0),
    st.floats(0.0, 20.0),
)
def test_split_shares_sum_to_rhs(seed, split, barrier, ti, tj):
    rng = np.random.default_rng(seed)
    p, v = pair_state(rng, safe=rng.random() < 0.7)
    gamma = float(rng.uniform(0.2, 5.0))
    I, J = np.array([0]), np.array([1])
    w = SafetyFilter(FilterConfig()).pair_weights(np.array([ti, tj]), None, I, J)
    rows = pair_rows.double_integrator_rows(
        p, v, w, I, J, pair_rows.BarrierSpec(gamma, DS, LO, HI, barrier, split), cull=False
    )
    rhs, exists = rhs_reference(p, v, barrier, gamma)
    if not exists:
        assert not rows.mask.any()
        return
    assert rows.mask[:, 0].all()
    s_i, s_j = rows.b[0, 0], rows.b[1, 0]
    assert s_i + s_j == pytest.approx(rhs, rel=1e-9, abs=1e-9)
    c = 1.0 if barrier == "braking" else 2.0
    dp = p[0] - p[1]
    np.testing.assert_allclose(rows.A[0, 0], -c * dp)
    np.testing.assert_allclose(rows.A[1, 0], c * dp)
    if split == "capability":
        cap = c * A_MAX * np.abs(dp).sum()
        if rows.unrecoverable[0, 0]:
            assert rhs < -2 * cap
            assert s_i == pytest.approx(rhs / 2)
        else:
            assert -cap - 1e-9 <= s_i <= rhs + cap + 1e-9
    if split == "paper":
        assert s_i == pytest.approx(w[0, 0] * rhs, rel=1e-12, abs=1e-12)


@settings(max_examples=400, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.floats(0.0, 100.0),
    st.floats(0.0, 100.0),
    st.sampled_from([None, 0.01, 0.05]),
)
def test_one_neighbour_is_always_feasible(seed, ti, tj, dt):
    """Braking barrier + capability split, h >= 0: every agent's QP has a solution."""
    rng = np.random.default_rng(seed)
    p, v = pair_state(rng)
    f = SafetyFilter(
        FilterConfig(
            gamma=float(rng.uniform(0.1, 5.0)),
            safety_radius=DS,
            u_max=A_MAX,
            dynamics="double_integrator",
            barrier="braking",
            dt=dt,
        )
    )
    nominal = rng.uniform(-A_MAX, A_MAX, (2, 2))
    res = f.filter(p, nominal, [ti, tj], velocities=v)
    assert res.feasible.all()
    assert res.n_unrecoverable_pairs == 0


def test_random_pairs_keep_their_distance_under_zoh():
    """100 isolated pairs, |a_k| <= 5, exact zero-order hold at dt = 0.01, 15 s each.

    The pairs are simulated in one batch, 10 km apart, with a 1 km neighbour radius, so no row
    ever couples two pairs.
    """
    rng = np.random.default_rng(2024)
    n_pairs, dt = 100, 0.01
    p = np.zeros((2 * n_pairs, 2))
    v = np.zeros((2 * n_pairs, 2))
    offsets = np.repeat(np.stack([np.arange(n_pairs) * 1e4, np.zeros(n_pairs)], 1), 2, axis=0)
    for k in range(n_pairs):
        p[2 * k : 2 * k + 2], v[2 * k : 2 * k + 2] = pair_state(rng)
    goals = -1.5 * p + offsets
    p += offsets
    v_des = rng.uniform(10, 25, (2 * n_pairs, 1))
    theta = rng.uniform(0, 10, 2 * n_pairs)
    f = SafetyFilter(
        FilterConfig(
            gamma=1.0,
            safety_radius=DS,
            u_max=A_MAX,
            dt=dt,
            dynamics="double_integrator",
            barrier="braking",
            neighbor_radius=1000.0,
        )
    )
    worst, n_infeasible = np.inf, 0
    for _ in range(1500):
        to_goal = goals - p
        nominal = 2.0 * (to_goal / np.linalg.norm(to_goal, axis=1, keepdims=True) * v_des - v)
        norm = np.linalg.norm(nominal, axis=1, keepdims=True)
        nominal *= np.minimum(1.0, A_MAX / np.maximum(norm, 1e-12))
        res = f.filter(p, nominal, theta, velocities=v)
        n_infeasible += int((~res.feasible).sum())
        p, v = double_integrator_step(p, v, res.actions, dt)
        gaps = np.linalg.norm(p[0::2] - p[1::2], axis=1) - DS
        worst = min(worst, float(gaps.min()))
    print(f"worst margin over 100 pairs: {worst:.6f} m, infeasible agent-steps: {n_infeasible}")
    assert n_infeasible == 0
    assert worst >= 0.0
