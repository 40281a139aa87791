"""The backup barrier of the double integrator (``docs/double_integrator.md``): the lemmas of its
proof as property tests, every QP feasible in 10,000 states built at h = 0 (head-on, crossing,
overtaking, 3 to 8 agents converging), crowds that never come closer than r_i + r_j nor lose
feasibility while h >= 0 from millimetres to kilometres, walls, and the culled filter equal to the
all-pairs one."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rsvo_env.dynamics import double_integrator_step
from rsvo_env.dynamics.barriers import backup as bb
from rsvo_env.dynamics.barriers import segment as sb
from rsvo_env.dynamics.barriers import stopping
from rsvo_env.filter.safety import FilterConfig, SafetyFilter
from rsvo_env.geometry import pairs
from rsvo_env.geometry.obstacles import Obstacles
from rsvo_env.qp import solve as solvers
from tests.support.backup_states import (
    cluster,
    drive,
    into_safe_set,
    obstacle_h,
    pair_h,
    safe_crowd,
)
from tests.support.segment_states import crowd_pair_h, seg_obstacle_h

TOL = 1e-9  # relative: a pair counts as touching below (r_i + r_j)(1 - TOL)
scales = st.sampled_from([1e-3, 1.0, 1e3])
unit = st.floats(0.0, 1.0)


def config(dt, gamma_dt, scale=1.0, barrier="backup", **kw):
    return FilterConfig(
        gamma=gamma_dt / dt,
        safety_radius=scale,
        u_max=3.0 * scale,
        dt=dt,
        dynamics="double_integrator",
        barrier=barrier,
        **kw,
    )


# the crowds run under both barriers whose backup meets every row, each checked by its own h
# (the segment barrier's own tests: tests/dynamics/test_segment_barrier.py)
BARRIERS = ("backup", "segment")
HS = {"backup": (pair_h, obstacle_h), "segment": (crowd_pair_h, seg_obstacle_h)}


# --- the lemmas ---------------------------------------------------------------------------


@given(s=st.floats(0.0, 50.0), angle=st.floats(0, 2 * np.pi), c=st.floats(0.05, 10.0),
       dt=st.floats(1e-3, 2.0), scale=scales)  # fmt: skip
def test_the_backup_gives_up_at_least_the_reach_it_travels(s, angle, c, dt, scale):
    """Lemma 1: |p+ - p| + L(|v+|) <= L(|v|) under the backup, which stays in the disk |a| <= c."""
    v = np.array([[np.cos(angle), np.sin(angle)]]) * s * scale
    c_ = np.array([c * scale])
    beta = stopping.backup_action(v, c_, dt)
    assert np.linalg.norm(beta) <= c_[0] * (1 + 1e-12)
    p1, v1 = double_integrator_step(np.zeros((1, 2)), v, beta, dt)
    before = stopping.stopping_reach(np.linalg.norm(v, axis=1), c_, dt)[0]
    after = stopping.stopping_reach(np.linalg.norm(v1, axis=1), c_, dt)[0] + np.linalg.norm(p1)
    assert after <= before + 1e-12 * (before + scale * dt * dt * c)


@given(s=st.floats(0.0, 30.0), angle=st.floats(0, 2 * np.pi), c=st.floats(0.05, 10.0),
       dt=st.floats(1e-3, 2.0), r=unit, x=unit, y=unit, scale=scales)  # fmt: skip
def test_the_remainder_bounds_the_reach_over_the_trust_box(s, angle, c, dt, r, x, y, scale):
    """Lemma 3: L(|v + dt a|) <= L(|v + dt beta|) + g . (a - beta) + R(rho) for every a with
    |a - beta|_inf <= rho (here up to the box's far corner)."""
    v = np.array([[np.cos(angle), np.sin(angle)]]) * s * scale
    c_ = np.array([c * scale])
    t = stopping.agent_terms(v, -c_[:, None] * np.ones(2), c_[:, None] * np.ones(2), dt)
    rho = r * 2.0 * c * scale
    a = t.beta + rho * (2.0 * np.array([[x, y]]) - 1.0)
    w = v + dt * a
    lhs = stopping.stopping_reach(np.linalg.norm(w, axis=1), c_, dt)[0]
    wb = v + dt * t.beta
    tangent = (
        stopping.stopping_reach(np.linalg.norm(wb, axis=1), c_, dt)[0] + (t.g * (a - t.beta)).sum()
    )
    bound = tangent + stopping.remainder(np.array([rho]), c_, dt)[0]
    assert lhs <= bound + 1e-12 * (abs(lhs) + scale * dt * dt * c)


@given(tau=st.floats(0.0, 1e6), c=st.floats(1e-3, 1e3), dt=st.floats(1e-3, 2.0))
def test_the_trust_radius_inverts_the_remainder(tau, c, dt):
    rho = stopping.trust_radius(np.array([tau]), np.array([c]), dt)
    assert rho[0] >= 0
    assert stopping.remainder(rho, np.array([c]), dt)[0] == pytest.approx(tau, rel=1e-9, abs=1e-300)


# --- every QP feasible at h = 0 -------------------------------------------------------------


def at_zero(p, v, radii, a, dt):
    """The positions scaled about each cluster's centre so that its tightest pair has h = 0."""
    E, k = p.shape[:2]
    I, J = np.triu_indices(k, 1)
    L = stopping.stopping_reach(np.linalg.norm(v, axis=-1), a, dt)
    centre = p.mean(axis=1, keepdims=True)
    q = p - centre
    need = (radii[:, I] + radii[:, J] + L[:, I] + L[:, J]) / np.linalg.norm(
        q[:, I] - q[:, J], axis=-1
    )
    return centre + q * need.max(axis=1)[:, None, None]


FAMILIES = [("head-on", 2, 1505), ("crossing", 2, 1505), ("overtaking", 2, 1505)] + [
    ("converging", k, 931) for k in range(3, 9)
]


@pytest.mark.parametrize("family, k, E", FAMILIES)
def test_every_qp_is_feasible_in_states_built_at_h_zero(family, k, E):
    """10,101 clusters in all, each with its tightest pair at h = 0 (the rest >= 0): with any
    nominal every agent's QP is feasible, and after the step every pair keeps
    h+ >= (1 - gamma dt) h, so none comes below r_i + r_j. dt 0.01 - 2, gamma dt up to 1,
    millimetres to kilometres, theta 0 - 10 (with zeros)."""
    rng = np.random.default_rng(k * 31 + len(family))
    I, J = np.triu_indices(k, 1)
    feasible_all, worst_drop = True, np.inf
    for dt, gamma_dt, scale in (
        # the backup barrier accepts any dt: steps far longer than a body's braking time too
        [
            (0.01, 1.0, 1e-3),
            (0.05, 0.1, 1.0),
            (0.1, 1.0, 1e3),
            (0.1, 0.5, 1.0),
            (0.02, 0.7, 1e3),
            (0.5, 1.0, 1.0),
            (2.0, 0.5, 1e-3),
        ]
    ):
        m = E // 7
        p, v, radii, a = cluster(rng, family, m, k, scale)
        p = at_zero(p, v, radii, a, dt)
        theta = rng.uniform(0, 10, (m, k)) * (rng.uniform(size=(m, k)) > 0.1)
        nominal = rng.uniform(-1, 1, (m, k, 2)) * a[..., None]
        flt = SafetyFilter(config(dt, gamma_dt, scale))
        res = flt.filter(p, nominal, theta, velocities=v, radii=radii, u_max=a)
        feasible_all &= bool(res.feasible.all())
        h0 = np.stack([pair_h(p[e], v[e], radii[e], a[e], dt, I, J)[0] for e in range(m)])
        # rounding is relative to the cluster's extent
        extent = np.linalg.norm(p[:, I] - p[:, J], axis=-1).max(axis=1, keepdims=True)
        assert (np.abs(h0.min(axis=1, keepdims=True)) <= 1e-12 * extent).all()
        p1, v1 = double_integrator_step(p, v, res.actions, dt)
        h1 = np.stack([pair_h(p1[e], v1[e], radii[e], a[e], dt, I, J)[0] for e in range(m)])
        worst_drop = min(worst_drop, float(((h1 - (1 - gamma_dt) * h0) / extent).min()))
    assert feasible_all
    assert worst_drop >= -1e-12


# --- crowds -----------------------------------------------------------------------------------


@pytest.mark.parametrize("barrier", BARRIERS)
@pytest.mark.parametrize(
    "n, steps, dt, gamma_dt, scale, speed",
    [
        (100, 2000, 0.05, 0.1, 1.0, 0.0),
        (100, 1000, 0.1, 1.0, 1e-3, 4.0),
        (100, 1000, 0.01, 0.5, 1e3, 4.0),
        (1000, 150, 0.05, 1.0, 1.0, 4.0),
    ],
)
def test_crowds_never_touch_and_stay_feasible(n, steps, dt, gamma_dt, scale, speed, barrier):
    """Random crowds (radii 0.2 - 1.2, a_max 0.5 - 3 per agent, theta 0 - 10) from rest or from
    random velocities inside the safe set, driven across each other: no pair ever below (r_i +
    r_j)(1 - 1e-9), no infeasible QP while every h >= 0. (benchmarks/studies/double_integrator.py
    runs the full campaign: N = 100 and 1,000, 2,000 steps.)"""
    rng = np.random.default_rng(n + steps)
    p, v, radii, a, goals, theta = safe_crowd(rng, n, scale, speed)
    I, J = np.triu_indices(n, 1)
    v = into_safe_set(p, v, radii, a, dt, I, J)
    flt = SafetyFilter(config(dt, gamma_dt, scale, barrier=barrier))
    worst, _, infeasible, *_ = drive(
        flt, p, v, goals, radii, a, theta, dt, steps, 2.0 * scale, I, J, hs=HS[barrier]
    )
    assert infeasible == 0
    assert worst >= 1.0 - TOL


@pytest.mark.parametrize("barrier", BARRIERS)
def test_culled_filter_equals_all_pairs(barrier):
    """A 300-agent crowd in motion, theta with zeros (pairs searched at every distance): each
    step's actions and flags are those of the rows over all pairs, to 1e-12 of the box."""
    rng = np.random.default_rng(7)
    n, dt = 300, 0.05
    p, v, radii, a, goals, theta = safe_crowd(rng, n, 1.0, 3.0, spacing=3.6)
    theta[::37] = 0.0
    I, J = np.triu_indices(n, 1)
    v = into_safe_set(p, v, radii, a, dt, I, J)
    flt = SafetyFilter(config(dt, 0.5, barrier=barrier))
    rows_of = {"backup": bb.backup_rows, "segment": sb.segment_rows}[barrier]
    Ia, Ja = pairs.all_pairs(n)
    checked = 0
    for step in range(60):
        u = np.clip(2.0 * (goals - p) - v, -a[:, None], a[:, None])
        res = flt.filter(p, u, theta, velocities=v, radii=radii, u_max=a)
        if step % 6 == 0:
            w = flt.pair_weights(theta, None, Ia, Ja)
            boxes = stopping.AgentBoxes(radii, -np.c_[a, a], np.c_[a, a])
            rows, _ = rows_of(p, v, w, Ia, Ja, flt.config.gamma, dt, boxes, cull=False)
            ua, fa = solvers.solve(
                "exact", u, rows.flat_A, rows.flat_b, rows.offsets, -np.c_[a, a], np.c_[a, a]
            )[:2]
            assert np.array_equal(fa, res.feasible)
            assert np.abs(ua - res.actions).max() <= 1e-12 * a.max()
            assert res.rows.n_pairs < len(Ia)  # the search did cull
            checked += 1
        p, v = double_integrator_step(p, v, res.actions, dt)
    assert checked == 10


# --- walls and circles ----------------------------------------------------------------------


def field(rng, scale):
    """A 40 x 40 field: 10 circles and 6 walls of a thickness."""
    circles = np.c_[rng.uniform(5, 35, (10, 2)), rng.uniform(0.5, 2.0, 10)]
    mid = rng.uniform(8, 32, (6, 2))
    ang = rng.uniform(0, np.pi, 6)
    half = np.stack([np.cos(ang), np.sin(ang)], -1) * rng.uniform(1.5, 4.0, (6, 1))
    walls = np.stack([mid - half, mid + half], axis=1)
    return Obstacles.of(circles * scale, walls * scale, rng.uniform(0.1, 0.4, 6) * scale)


@pytest.mark.parametrize("barrier", BARRIERS)
@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
def test_crowds_driven_through_walls_and_circles_never_touch(scale, barrier):
    """40 double integrators cross a field of circles and walls toward goals beyond it: no body
    penetrates an obstacle or another body, no infeasible QP while every h >= 0."""
    rng = np.random.default_rng(int(np.log10(scale)) + 5)
    obstacles = field(rng, scale)
    n, dt = 40, 0.05
    side = rng.choice([-1.0, 1.0], n)
    p = np.c_[20 + side * 24 + rng.uniform(-2, 2, n), np.linspace(2, 38, n)] * scale
    goals = np.c_[20 - side * 24, rng.uniform(2, 38, n)] * scale
    radii = rng.uniform(0.2, 0.4, n) * scale
    a = rng.uniform(0.5, 3.0, n) * scale
    theta = rng.uniform(0, 10, n)
    I, J = np.triu_indices(n, 1)
    v = into_safe_set(p, np.zeros((n, 2)), radii, a, dt, I, J, obstacles.capsules)
    flt = SafetyFilter(config(dt, 0.5, scale, barrier=barrier))
    worst, worst_o, infeasible, p, _ = drive(
        flt, p, v, goals, radii, a, theta, dt, 1200, 3.0 * scale, I, J, obstacles, hs=HS[barrier]
    )
    assert infeasible == 0
    assert worst >= 1.0 - TOL and worst_o >= 1.0 - TOL
    assert worst < 1.2 and worst_o < 1.2  # bodies came close to each other and to obstacles


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
def test_a_double_integrator_brakes_before_a_wall_from_any_speed_it_can_stop(scale):
    """Agents at full throttle into a wall, each from the speed at which its stopping reach just
    fits (h = 0) or less, at every angle: none penetrates it, every QP feasible."""
    rng = np.random.default_rng(3)
    n, dt = 50, 0.02
    wall = Obstacles.of(None, np.array([[[0.0, -1e5], [0.0, 1e5]]]) * scale, 0.2 * scale)
    radii = rng.uniform(0.2, 1.0, n) * scale
    a = rng.uniform(0.5, 3.0, n) * scale
    ang = rng.uniform(-1.3, 1.3, n)
    heading = np.c_[np.cos(ang), np.sin(ang)]
    speed = rng.uniform(0.2, 1.0, n) * 20.0 * scale
    x0 = -(0.2 * scale + radii + stopping.stopping_reach(speed, a, dt))  # h = 0 against the wall
    p = np.c_[x0, np.arange(n) * 1000.0 * scale]  # beyond each other's stopping reaches
    v = heading * speed[:, None]
    flt = SafetyFilter(config(dt, 1.0, scale))
    worst = np.inf
    for _ in range(int(25.0 / dt)):
        u = heading * a[:, None] / np.abs(heading).max(axis=1, keepdims=True)
        res = flt.filter(p, u, np.ones(n), velocities=v, radii=radii, u_max=a, obstacles=wall)
        assert res.feasible.all()
        p, v = double_integrator_step(p, v, res.actions, dt)
        worst = min(worst, float(obstacle_h(p, v, radii, a, dt, wall.capsules)[1].min()))
    assert 1.0 - TOL <= worst < 1.01  # at the edge: one came within 1 % of its radius


# --- the barrier as the filter's default ------------------------------------------------------


def test_continuous_time_rows_admit_the_backup():
    """Without dt the rows are the barrier's rate (relative degree one): braking along the
    velocity meets every row of an agent with any number of neighbours while every h >= 0."""
    rng = np.random.default_rng(11)
    for k in range(2, 9):
        p, v, radii, a = cluster(rng, "converging", 200, k, 1.0)
        p = at_zero(p, v, radii, a, None)
        for e in range(200):
            I, J = np.triu_indices(k, 1)
            w = np.c_[np.full(len(I), 0.3), np.full(len(I), 0.7)]
            boxes = stopping.AgentBoxes(radii[e], -np.c_[a[e], a[e]], np.c_[a[e], a[e]])
            rows, _ = bb.backup_rows(p[e], v[e], w, I, J, 2.0, None, boxes)
            beta = stopping.backup_action(v[e], a[e], None)
            lhs = (rows.flat_A * beta[rows.owner]).sum(-1)
            assert (lhs <= rows.flat_b + 1e-12 * (1 + np.abs(rows.flat_b))).all()


def test_backup_takes_walls_and_the_braking_barrier_does_not():
    cfg = FilterConfig(dynamics="double_integrator", dt=0.05, barrier="backup")
    from rsvo_env.scenarios.scenes import Scene

    kw = {
        "starts": [[0, 0], [10, 0]],
        "goals": [[10, 0], [0, 0]],
        "dynamics": "double_integrator",
        "walls": [((5, 3), (5, 8))],
    }
    assert Scene(**kw).num_obstacles == 1
    wall = Obstacles.of(None, [((5, 3), (5, 8))], 0.1)
    args = ([[0, 0], [10, 0]], [[1, 0], [-1, 0]], [1, 2])
    SafetyFilter(cfg).filter(*args, velocities=np.zeros((2, 2)), obstacles=wall)
    braking = FilterConfig(dynamics="double_integrator", dt=0.05, barrier="braking")
    with pytest.raises(ValueError, match="walls are not available for the double_integrator"):
        SafetyFilter(braking).filter(*args, velocities=np.zeros((2, 2)), obstacles=wall)


def test_an_unsafe_start_is_reported_and_the_nominal_not_passed_through():
    """Two agents already closer than their stopping reaches, closing head-on: the filter
    reports h < 0, asks them to recover at the rate gamma dt (h+ >= (1 - gamma dt) h) and says
    where it cannot (``feasible`` False); the nominal is not passed through; agents at the same
    point have no direction to part along and are reported infeasible."""
    dt, gamma_dt = 0.05, 0.5
    flt = SafetyFilter(config(dt, gamma_dt))
    p = np.array([[0.0, 0.0], [2.0, 0.0]])
    v = np.array([[3.0, 0.0], [-3.0, 0.0]])
    nominal = np.array([[3.0, 0.0], [-3.0, 0.0]])
    a, radii, I, J = np.array([3.0, 3.0]), np.full(2, 0.5), np.array([0]), np.array([1])
    res = flt.filter(p, nominal, [1.0, 1.0], velocities=v)
    assert res.min_h < 0
    assert (np.abs(res.actions - nominal) > 1.0).any(axis=1).all()
    h0 = pair_h(p, v, radii, a, dt, I, J)[0]
    p1, v1 = double_integrator_step(p, v, res.actions, dt)
    h1 = pair_h(p1, v1, radii, a, dt, I, J)[0]
    assert not res.feasible.all() or h1 >= (1 - gamma_dt) * h0 - 1e-12
    assert h1 > h0  # the least-violating action still brakes
    same = flt.filter(np.zeros((2, 2)), nominal, [1.0, 1.0], velocities=v)
    assert not same.feasible.any()


@pytest.mark.parametrize("dt", [0.05, None])
@pytest.mark.parametrize("seed", range(4))
def test_outside_the_safe_set_culling_is_exact_on_feasible_agents(dt, seed):
    """Crowds of 68 to 92 double integrators at random velocities, not scaled into the safe
    set (the default segment barrier, dt 0.05 and continuous time): the culled filter flags the
    same agents infeasible as the rows over all pairs, and every feasible agent's action is the
    all-pairs one to 1e-12 of the box. An infeasible agent's least-violating action is that of
    the rows examined and may differ (docs/double_integrator.md, "Which pairs are examined")."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(68, 93))
    p, v, radii, a, goals, theta = safe_crowd(rng, n, 1.0, 4.0, spacing=2.6)
    flt = SafetyFilter(
        FilterConfig(gamma=10.0, safety_radius=1.0, u_max=3.0, dt=dt, dynamics="double_integrator")
    )
    Ia, Ja = pairs.all_pairs(n)
    lo, hi = -np.c_[a, a], np.c_[a, a]
    boxes = stopping.AgentBoxes(radii, lo, hi)
    infeasible = 0
    for _ in range(3):
        u = np.clip(2.0 * (goals - p) - v, lo, hi)
        res = flt.filter(p, u, theta, velocities=v, radii=radii, u_max=a)
        w = flt.pair_weights(theta, None, Ia, Ja)
        rows, _ = sb.segment_rows(p, v, w, Ia, Ja, flt.config.gamma, dt, boxes, cull=False)
        ua, fa = solvers.solve("exact", u, rows.flat_A, rows.flat_b, rows.offsets, lo, hi)[:2]
        assert np.array_equal(fa, res.feasible)
        assert np.abs(ua - res.actions)[fa].max(initial=0.0) <= 1e-12 * a.max()
        infeasible += int((~fa).sum())
        p, v = double_integrator_step(p, v, res.actions, 0.05)
    assert infeasible > 0  # the family reaches outside the safe set
