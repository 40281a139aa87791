"""The stopping-segment barrier of the double integrator (``docs/double_integrator.md``, "The
stopping-segment barrier"): the lemma of its rows as a property test, the theorem attacked in
10,000 clusters built at h = 0 (head-on, crossing, overtaking, 3 to 8 converging, against walls,
wall corners and circles; millimetres to kilometres), crowds that never touch, the culled filter
equal to the all-pairs one, and what the shape buys: touching agents at rest part, agents side by
side keep their speed."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rsvo_env.dynamics import double_integrator_step
from rsvo_env.dynamics.barriers import box, stopping
from rsvo_env.dynamics.barriers import segment as sb
from rsvo_env.filter.safety import FilterConfig, SafetyFilter
from rsvo_env.geometry.obstacles import Obstacles
from rsvo_env.geometry.segments import separation
from tests.support.backup_states import cluster
from tests.support.segment_states import at_zero, ends, obstacle_cluster, seg_obstacle_h, seg_pair_h

TOL = 1e-9  # relative: a pair counts as touching below (r_i + r_j)(1 - TOL)
scales = st.sampled_from([1e-3, 1.0, 1e3])
unit = st.floats(0.0, 1.0)


def config(dt, gamma_dt, scale=1.0, **kw):
    return FilterConfig(
        gamma=gamma_dt / dt,
        safety_radius=scale,
        u_max=3.0 * scale,
        dt=dt,
        dynamics="double_integrator",
        **kw,
    )


def lowest(n, p, v, a, dt):
    """min over the agent's stopping segment of n . x."""
    p0, p1 = ends(p, v, a, dt)
    return np.minimum((n * p0).sum(-1), (n * p1).sum(-1))


# --- the lemma --------------------------------------------------------------------------------


@settings(deadline=None)  # the first example compiles the kernels
@given(s=st.floats(0.0, 30.0), angle=st.floats(0, 2 * np.pi), normal=st.floats(0, 2 * np.pi),
       c=st.floats(0.05, 10.0), dt=st.floats(1e-3, 2.0), h=st.floats(0.0, 2.0),
       x=unit, y=unit, scale=scales)  # fmt: skip
def test_rows_keep_the_segment_above_its_bound(s, angle, normal, c, dt, h, x, y, scale):
    """Eq. ``seg-rows``: the backup meets both rows, and every action of the agent's trust box
    that meets them keeps the lowest point of its next segment along the rows' normal n at least
    ``m - sigma`` (``sigma = omega gamma dt h``, h set within a few ``c dt^2`` of 0 so the rows
    bind)."""
    v = np.array([[np.cos(angle), np.sin(angle)]]) * s * scale
    box = np.array([[c, c]]) * scale
    L = stopping.stopping_reach(np.array([s * scale]), box[:, 0], dt)[0]
    p = np.zeros((1, 2))
    other = -np.array([[np.cos(normal), np.sin(normal)]]) * (L + 3.0 * scale)
    P, V = np.r_[p, other], np.r_[v, np.zeros((1, 2))]
    p0, p1 = ends(P, V, np.r_[box[:, 0], box[:, 0]], dt)
    dist = separation(p0[[0]] - other, p1[[0]] - other, 0 * other, 0 * other, p0[[0]] - other)[1][0]
    radii = np.array([0.5 * scale, dist - 0.5 * scale - h * c * scale * dt * dt])
    boxes = stopping.AgentBoxes(radii, -np.r_[box, box], np.r_[box, box])
    rows, _ = sb.segment_rows(
        P, V, np.array([[0.4, 0.6]]), np.array([0]), np.array([1]), 0.5 / dt, dt, boxes, cull=False
    )
    mine = rows.owner == 0
    A, b = rows.flat_A[mine], rows.flat_b[mine]
    n = -A[0] / (0.5 * dt * dt)
    beta = stopping.backup_action(v, box[:, 0], dt)
    tol = 1e-12 * scale * (1.0 + s * dt + c * dt * dt + L)
    assert (A @ beta[0] <= b + tol * (1 + np.abs(A).sum(-1))).all()
    # the farthest point toward a corner of the box that meets every row, on the way from beta
    corner = -box[0] + 2.0 * box[0] * np.array([x, y])
    t = np.linspace(0.0, 1.0, 257)[:, None]
    cand = beta[0] + t * (corner - beta[0])
    # (the backup itself meets the rows to the rounding allowed above: at h = 0 they bind there)
    a = cand[(cand @ A.T <= b + tol * (1 + np.abs(A).sum(-1))).all(axis=1)][-1]
    sigma = 0.4 * 0.5 * rows.pair_h[0]
    m = lowest(n, p, v, box[:, 0], dt)[0]
    p_next, v_next = double_integrator_step(p, v, a[None], dt)
    assert lowest(n, p_next, v_next, box[:, 0], dt)[0] >= m - sigma - tol


# --- the theorem attacked: every QP feasible at h = 0 -----------------------------------------

SETTINGS = [
    (0.01, 1.0, 1e-3),
    (0.05, 0.1, 1.0),
    (0.1, 1.0, 1e3),
    (0.1, 0.5, 1.0),
    (0.02, 0.7, 1e3),
    (0.5, 1.0, 1.0),
    (2.0, 0.5, 1e-3),
]
FAMILIES = (
    [("head-on", 2, 840), ("crossing", 2, 840), ("overtaking", 2, 840)]
    + [("converging", k, 840) for k in range(3, 9)]
    + [("wall", 2, 840), ("corner", 3, 840), ("circle", 3, 840)]
)


@pytest.mark.parametrize("family, k, E", FAMILIES)
def test_every_qp_is_feasible_in_states_built_at_h_zero(family, k, E):
    """10,080 clusters in all, each with its tightest h (over pairs and obstacles) at 0: with any
    nominal every agent's QP is feasible, and after the step every pair and obstacle keeps
    h+ >= (1 - gamma dt) h to 1e-12 of the cluster's extent. dt 0.01 - 2, gamma dt up to 1,
    millimetres to kilometres, theta 0 - 10 (with zeros)."""
    rng = np.random.default_rng(k * 31 + len(family))
    I, J = np.triu_indices(k, 1)
    feasible_all, worst_drop, m = True, np.inf, E // len(SETTINGS)
    for dt, gamma_dt, scale in SETTINGS:
        if family in ("wall", "corner", "circle"):
            p, v, radii, a, caps, centre = obstacle_cluster(rng, family, m, k, scale)
        else:
            (p, v, radii, a), caps = cluster(rng, family, m, k, scale), None
            centre = p.mean(axis=1, keepdims=True)
        p = at_zero(p, v, radii, a, dt, centre, caps)
        theta = rng.uniform(0, 10, (m, k)) * (rng.uniform(size=(m, k)) > 0.1)
        nominal = rng.uniform(-1, 1, (m, k, 2)) * a[..., None]
        kw = {} if caps is None else {"obstacles": Obstacles(caps)}
        flt = SafetyFilter(config(dt, gamma_dt, scale))
        res = flt.filter(p, nominal, theta, velocities=v, radii=radii, u_max=a, **kw)
        feasible_all &= bool(res.feasible.all())
        p1, v1 = double_integrator_step(p, v, res.actions, dt)
        h0 = [seg_pair_h(p, v, radii, a, dt, I, J)[0]]
        h1 = [seg_pair_h(p1, v1, radii, a, dt, I, J)[0]]
        if caps is not None:
            h0.append(seg_obstacle_h(p, v, radii, a, dt, caps)[0].reshape(m, -1))
            h1.append(seg_obstacle_h(p1, v1, radii, a, dt, caps)[0].reshape(m, -1))
        h0, h1 = np.concatenate(h0, axis=1), np.concatenate(h1, axis=1)
        extent = np.abs(p - centre).max(axis=(1, 2))[:, None] + scale
        assert (np.abs(h0.min(axis=1, keepdims=True)) <= 1e-12 * extent).all()
        worst_drop = min(worst_drop, float(((h1 - (1 - gamma_dt) * h0) / extent).min()))
    assert feasible_all
    assert worst_drop >= -1e-12


# --- what the shape buys ----------------------------------------------------------------------


def test_two_touching_agents_at_rest_part_and_arrive():
    """Issue 48's pair: radii 0.5, at rest 1 m apart (touching), goals 6 - 7 m away in opposite
    directions, the custom scene's own scripted controller: they part and arrive (the backup
    barrier, the stopping disk, holds them at u = 0 for ever), never closer than touching."""
    from rsvo_env.envs.vector import BatchedEnv

    kw = {
        "starts": [[0.0, 0.0], [1.0, 0.0]],
        "goals": [[-6.0, 0.0], [7.0, 0.0]],
        "dynamics": "double_integrator",
        "radii": [0.5, 0.5],
    }
    for barrier, arrives in (("segment", True), ("backup", False)):
        env = BatchedEnv("custom", num_envs=1, barrier=barrier, max_steps=3000, **kw)
        env.reset(seed=0)
        reached, moved = np.zeros(2, dtype=bool), 0.0
        for _ in range(3000):
            _, _, _, _, info = env.step(env.nominal_actions())
            assert info["feasible"].all() and (info["cost"] == 0).all()
            reached |= info["at_goal"][0]
            moved = max(moved, float(np.abs(info["u_safe"]).max()))
            if reached.all():
                break
        assert reached.all() == arrives and (moved > 0) == arrives, barrier


def test_side_by_side_at_full_speed_keep_their_speed():
    """Two agents 1.1 D apart moving side by side at the speed the scene asks: the filter leaves
    their speed alone (the disk would charge each the other's stopping reach)."""
    dt = 0.05
    flt = SafetyFilter(
        FilterConfig(gamma=10.0, safety_radius=1.0, u_max=1.0, dt=dt, dynamics="double_integrator")
    )
    disk = SafetyFilter(
        FilterConfig(
            gamma=10.0,
            safety_radius=1.0,
            u_max=1.0,
            dt=dt,
            dynamics="double_integrator",
            barrier="backup",
        )
    )
    for f, keeps in ((flt, True), (disk, False)):
        p, v = np.array([[0.0, 0.0], [0.0, 1.1]]), np.array([[2.0, 0.0], [2.0, 0.0]])
        for _ in range(200):
            res = f.filter(p, np.zeros((2, 2)), [1.0, 3.0], velocities=v)
            p, v = double_integrator_step(p, v, res.actions, dt)
        assert np.allclose(v, [[2.0, 0.0], [2.0, 0.0]], rtol=0, atol=1e-12) == keeps


def test_continuous_time_rows_admit_the_backup():
    """Without dt the rows are the rate of each segment's lowest end along n: braking along the
    velocity meets every row of an agent with any number of neighbours while every h >= 0."""
    rng = np.random.default_rng(11)
    for k in range(2, 9):
        p, v, radii, a = cluster(rng, "converging", 200, k, 1.0)
        p = at_zero(p, v, radii, a, None, p.mean(axis=1, keepdims=True))
        I, J = np.triu_indices(k, 1)
        w = np.c_[np.full(len(I), 0.3), np.full(len(I), 0.7)]
        for e in range(200):
            boxes = stopping.AgentBoxes(radii[e], -np.c_[a[e], a[e]], np.c_[a[e], a[e]])
            rows, _ = sb.segment_rows(p[e], v[e], w, I, J, 2.0, None, boxes)
            beta = stopping.backup_action(v[e], a[e], None)
            lhs = (rows.flat_A * beta[rows.owner]).sum(-1)
            assert (lhs <= rows.flat_b + 1e-12 * (1 + np.abs(rows.flat_b))).all()


def test_segment_is_the_default_and_the_others_stay_by_name():
    assert FilterConfig(dynamics="double_integrator", dt=0.05).barrier == "segment"
    wall = Obstacles.of(None, [((5, 3), (5, 8))], 0.1)
    args = ([[0, 0], [10, 0]], [[1, 0], [-1, 0]], [1, 2])
    for barrier in ("segment", "backup"):
        cfg = FilterConfig(dynamics="double_integrator", dt=0.05, barrier=barrier)
        assert SafetyFilter(cfg).filter(*args, velocities=np.zeros((2, 2)), obstacles=wall)
    with pytest.raises(ValueError, match="FilterConfig.barrier = 'disk'"):
        FilterConfig(dynamics="double_integrator", dt=0.05, barrier="disk")


def test_an_unsafe_start_is_reported_and_the_nominal_not_passed_through():
    """Two agents whose stopping segments overlap, closing head-on: the filter reports h < 0,
    asks them to recover at the rate gamma dt and says where it cannot (``feasible`` False); the
    nominal is not passed through; agents at one point are reported infeasible."""
    dt, gamma_dt = 0.05, 0.5
    flt = SafetyFilter(config(dt, gamma_dt))
    p = np.array([[0.0, 0.0], [2.0, 0.0]])
    v = np.array([[3.0, 0.0], [-3.0, 0.0]])
    nominal = np.array([[3.0, 0.0], [-3.0, 0.0]])
    a, radii, I, J = np.array([3.0, 3.0]), np.full(2, 0.5), np.array([0]), np.array([1])
    res = flt.filter(p, nominal, [1.0, 1.0], velocities=v)
    assert res.min_h < 0
    assert (np.abs(res.actions - nominal) > 1.0).any(axis=1).all()
    h0 = seg_pair_h(p, v, radii, a, dt, I, J)[0]
    p1, v1 = double_integrator_step(p, v, res.actions, dt)
    h1 = seg_pair_h(p1, v1, radii, a, dt, I, J)[0]
    assert not res.feasible.all() or h1 >= (1 - gamma_dt) * h0 - 1e-12
    # the least-violating action still brakes: the overlap of the two segments shrinks
    assert (np.linalg.norm(v1, axis=1) < np.linalg.norm(v, axis=1)).all()
    same = flt.filter(np.zeros((2, 2)), nominal, [1.0, 1.0], velocities=v)
    assert not same.feasible.any()


def at_a_big_obstacle(rng, kind, size, where, r, c, dt):
    """An agent whose stopping segment ends on the surface of a wall ``size`` long (0.1 r
    thick) or a circle of radius ``size``, ``where`` from the origin, heading at it up to 69
    degrees off the surface's normal at speed 0.5 to 3 (h = 0 to rounding): (p, v, Obstacles)."""
    ang = rng.uniform(0, 2 * np.pi)
    d = np.array([np.cos(ang), np.sin(ang)])
    normal = np.array([-d[1], d[0]])
    centre = where * np.array([np.cos(ang + 1.0), np.sin(ang + 1.0)])
    if kind == "wall":
        thick = 0.1 * r
        obstacles = Obstacles.of(
            walls=[[centre - 0.5 * size * d, centre + 0.5 * size * d]], thickness=thick
        )
        rho = obstacles.capsules[0, 4]  # the wall's half thickness
        q = centre + rng.uniform(-0.4, 0.4) * size * d + normal * (r + rho)
    else:
        obstacles = Obstacles.of(circles=[[*centre, size]])
        q = centre + normal * (r + size)
    tilt = rng.uniform(-1.2, 1.2)
    head = -(np.cos(tilt) * normal + np.sin(tilt) * d)
    s = rng.uniform(0.5, 3.0)
    L = s * s / (2.0 * c) + 0.5 * s * dt
    return (q - head * L)[None], (head * s)[None], obstacles


@pytest.mark.parametrize("kind", ["wall", "circle"])
@pytest.mark.parametrize("size", [1.0, 1e3, 1e5, 1e7])
@pytest.mark.parametrize("where", [0.0, 1e4, 5e6, 1e7])
def test_obstacles_up_to_1e7_in_size_and_position_keep_the_qp_feasible(kind, size, where):
    """A 1 m body with a 1 m/s^2 box whose stopping segment ends on a wall's or a circle's
    surface (h = 0), obstacles 1 m to 1e7 m in size and up to 1e7 m from the origin, 40
    placements each: every QP feasible and the next h >= 0 to the rounding of those
    coordinates (1e-15 of them). Beside a wall 2e7 m long 22 of 40 were infeasible: the bound
    along the separating direction carried the direction's rounding times the wall's length."""
    rng = np.random.default_rng(int(np.log10(size)) * 7 + int(where > 0))
    r, dt = 1.0, 0.05
    flt = SafetyFilter(
        FilterConfig(
            dynamics="double_integrator", u_max=1.0, safety_radius=2 * r, dt=dt, gamma=10.0
        )
    )
    c = box.braking_capability(np.array([[-1.0, -1.0]]), np.array([[1.0, 1.0]]))[0]
    rounding = 1e-15 * (size + where)
    for _ in range(40):
        p, v, obstacles = at_a_big_obstacle(rng, kind, size, where, r, c, dt)
        caps = obstacles.capsules
        assert seg_obstacle_h(p, v, np.array([r]), np.array([1.0]), dt, caps)[0].min() >= (
            -1e-6 - rounding
        )  # built at h = 0
        res = flt.filter(
            p,
            np.zeros((1, 2)),
            np.ones(1),
            velocities=v,
            radii=np.array([r]),
            u_max=np.array([1.0]),
            obstacles=obstacles,
        )
        assert res.feasible[0], (kind, size, where)
        p1, v1 = double_integrator_step(p, v, res.actions, dt)
        h1 = seg_obstacle_h(p1, v1, np.array([r]), np.array([1.0]), dt, caps)[0].min()
        assert h1 >= -rounding - 1e-12, (kind, size, where, h1)
