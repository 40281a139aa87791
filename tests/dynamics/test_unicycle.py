"""The unicycle through its look-ahead point: bodies (true axle positions) never overlap, the
inputs stay in their bounds through every step, the closed-form step is the unicycle's own
motion under the look-ahead hold, and obstacles hold as for the single integrator."""

import numpy as np
import pytest

import rsvo_env
from rsvo_env.dynamics import single_integrator, unicycle_step
from rsvo_env.dynamics.unicycle import heading_vectors, rotate_rows
from rsvo_env.filter.safety import FilterConfig, SafetyFilter
from rsvo_env.geometry import pairs
from rsvo_env.geometry.bodies import Bodies
from rsvo_env.geometry.obstacles import Obstacles
from rsvo_env.qp import exact

V_MAX, W_MAX = 1.0, 2.0


def crowd(n: int, seed: int, scale: float = 1.0):
    rng = np.random.default_rng(seed)
    radii = rng.uniform(0.2, 0.5, n)
    side = int(np.ceil(np.sqrt(n)))
    grid = np.stack(np.meshgrid(np.arange(side), np.arange(side)), -1).reshape(-1, 2)[:n]
    x = grid * 1.6 + rng.uniform(-0.1, 0.1, (n, 2))  # look-ahead points apart too
    headings = rng.uniform(-np.pi, np.pi, n)
    goals = x[rng.permutation(n)]
    theta = rng.uniform(0.0, 10.0, n)
    return x * scale, headings, goals * scale, theta, radii * scale


def nominal(p, headings, goals, l, v_max):
    """Drive the look-ahead point straight at the goal, as (v, w)."""
    e = heading_vectors(headings)
    c = goals - (p + l * e)
    dist = np.linalg.norm(c, axis=1, keepdims=True)
    c = c / np.maximum(dist, 1e-300) * np.minimum(dist, v_max)
    along = (e * c).sum(1)
    across = e[:, 0] * c[:, 1] - e[:, 1] * c[:, 0]
    return np.c_[along, across / l]


def inputs_through_the_step(u, l, dt, k=8):
    """(v, w) of the look-ahead hold at k instants of the step (they vary within it)."""
    c = np.hypot(u[:, 0], l * u[:, 1])
    psi0 = np.arctan2(-l * u[:, 1], u[:, 0])  # heading minus the direction of c
    t = np.linspace(0, dt, k)[:, None]
    psi = 2 * np.arctan(np.tan(psi0 / 2) * np.exp(-c * t / l))
    return c * np.cos(psi), -c / l * np.sin(psi)


@pytest.mark.parametrize(
    "n,steps,l_ratio,scale,gamma",
    [
        (20, 200, 0.05, 1.0, 10.0),
        (20, 200, 0.5, 1e-3, 20.0),
        (150, 120, 0.2, 1e3, 10.0),
        (150, 120, 0.5, 1.0, 20.0),
        (1000, 30, 0.3, 1.0, 10.0),
    ],
)  # fmt: skip  (gamma 20: gamma dt = 1, the edge)
def test_bodies_never_overlap_and_inputs_stay_in_bounds(n, steps, l_ratio, scale, gamma):
    p, th, goals, theta, radii = crowd(n, n, scale)
    l, dt = l_ratio * 0.2 * scale, 0.05
    cfg = FilterConfig(
        dynamics="unicycle",
        lookahead=l,
        w_max=W_MAX,
        u_max=V_MAX * scale,
        u_min=0.0,
        gamma=gamma,
        dt=dt,
    )
    flt = SafetyFilter(cfg)
    I, J = pairs.all_pairs(n)
    worst = np.inf
    for _ in range(steps):
        res = flt.filter(
            p, nominal(p, th, goals, l, V_MAX * scale), theta, headings=th, radii=radii
        )
        assert res.feasible.all()
        v, w = inputs_through_the_step(res.actions, l, dt)
        tol = 1e-12 * scale
        assert (v >= -tol).all() and (v <= V_MAX * scale + tol).all()
        assert (np.abs(w) <= W_MAX * (1 + 1e-12)).all()
        p, th = unicycle_step(p, th, res.actions, l, dt)
        gap = np.linalg.norm(p[I] - p[J], axis=1) / (radii[I] + radii[J])
        worst = min(worst, float(gap.min()))
    assert worst >= 1.0 - 1e-9
    assert worst < 1.0 + 2 * l_ratio + 0.3, "the crowd never came close: nothing was tested"


def test_the_step_is_the_unicycle_under_the_look_ahead_hold():
    """RK4 on p' = v e, theta' = w with (v, w) from the hold (q' = c fixed) matches the closed
    form, and the look-ahead point moves in a straight line."""
    rng = np.random.default_rng(0)
    p, th = rng.normal(size=(50, 2)), rng.uniform(-np.pi, np.pi, 50)
    u = np.c_[rng.uniform(0, 0.9, 50), rng.uniform(-2, 2, 50)]
    l, dt = 0.15, 0.2
    e = heading_vectors(th)
    c = np.stack(
        [e[:, 0] * u[:, 0] - e[:, 1] * l * u[:, 1], e[:, 1] * u[:, 0] + e[:, 0] * l * u[:, 1]], -1
    )

    def f(state):
        hp = state[:, 2]
        eh = heading_vectors(hp)
        v = (eh * c).sum(1)
        w = (eh[:, 0] * c[:, 1] - eh[:, 1] * c[:, 0]) / l
        return np.c_[v[:, None] * eh, w]

    s = np.c_[p, th]
    h = dt / 2000
    for _ in range(2000):
        k1 = f(s)
        k2 = f(s + h / 2 * k1)
        k3 = f(s + h / 2 * k2)
        k4 = f(s + h * k3)
        s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    p1, th1 = unicycle_step(p, th, u, l, dt)
    np.testing.assert_allclose(p1, s[:, :2], atol=1e-10)
    np.testing.assert_allclose(np.angle(np.exp(1j * (th1 - s[:, 2]))), 0, atol=1e-10)
    np.testing.assert_allclose(p1 + l * heading_vectors(th1), p + l * e + dt * c, atol=1e-12)


def test_unicycles_stop_at_obstacles():
    obstacles = Obstacles.of(
        circles=[(0.0, 0.0, 1.0)], walls=[((3.0, -2.0), (3.0, 2.0))], thickness=0.2
    )
    l = 0.1
    flt = SafetyFilter(
        FilterConfig(
            dynamics="unicycle", lookahead=l, w_max=W_MAX, u_max=V_MAX, gamma=10.0, dt=0.05
        )
    )
    p = np.array([[-4.0, 0.05], [6.0, 0.5]])
    th = np.array([0.3, np.pi - 0.2])
    goals = np.array([[4.0, 0.0], [0.0, 0.5]])
    radii = np.array([0.3, 0.4])
    for _ in range(400):
        res = flt.filter(
            p,
            nominal(p, th, goals, l, V_MAX),
            np.ones(2),
            headings=th,
            radii=radii,
            obstacles=obstacles,
        )
        assert res.feasible.all()
        p, th = unicycle_step(p, th, res.actions, l, 0.05)
        assert (obstacles.clearance(p, radii) >= -1e-9).all()
    # each stopped in front of its obstacle, its look-ahead point at the enlarged distance
    assert obstacles.clearance(p, radii).max() < 2 * l + 0.05


def test_unicycle_config_is_checked():
    with pytest.raises(ValueError, match="needs lookahead"):
        FilterConfig(dynamics="unicycle", w_max=1.0)
    with pytest.raises(ValueError, match="must be able to stop"):
        FilterConfig(dynamics="unicycle", lookahead=0.1, w_max=1.0, u_min=0.2, u_max=1.0)
    with pytest.raises(ValueError, match="lookahead \\* w_max"):
        FilterConfig(dynamics="unicycle", lookahead=0.5, w_max=3.0, u_max=1.0)
    with pytest.raises(ValueError, match="FilterConfig.lookahead = -0.1"):
        FilterConfig(dynamics="unicycle", lookahead=-0.1, w_max=1.0)
    flt = SafetyFilter(FilterConfig(dynamics="unicycle", lookahead=0.1, w_max=1.0))
    x = np.array([[0.0, 0.0], [5.0, 0.0]])
    with pytest.raises(ValueError, match="headings are required"):
        flt.filter(x, np.zeros((2, 2)), np.ones(2))
    with pytest.raises(ValueError, match=r"headings\[1\] = nan is not finite \(agent 1\)"):
        flt.filter(x, np.zeros((2, 2)), np.ones(2), headings=[0.0, np.nan])
    with pytest.raises(ValueError, match=r"headings has shape \(3,\)"):
        flt.filter(x, np.zeros((2, 2)), np.ones(2), headings=np.zeros(3))
    with pytest.raises(ValueError, match=r"u_max\[0\] = 0.05 must be above lookahead \* w_max"):
        flt.filter(x, np.zeros((2, 2)), np.ones(2), headings=np.zeros(2), u_max=[0.05, 1.0])


def every_row(flt, p, th, nom, theta, radii, holo):
    """The definition: the single integrator's rows of every pair on the look-ahead points
    (bodies grown by l), turned into each agent's body frame, nothing culled; the QP's
    solution as (v, w)."""
    cfg, n = flt.config, len(p)
    bodies = Bodies.of(cfg, 1, n, radii)
    if holo is not None:
        bodies = bodies.with_holonomic(holo, cfg.u_max, cfg.lookahead)
    q, nom_b, row_bodies, rotation = cfg.model.lift(cfg, p[None], nom[None], bodies, th[None])
    I, J = pairs.all_pairs(n)
    rows = single_integrator.single_integrator_rows(
        q[0],
        flt.pair_weights(theta, None, I, J),
        I,
        J,
        cfg.gamma,
        row_bodies.radii,
        row_bodies.lo,
        row_bodies.hi,
        cull=False,
    )
    A = rotate_rows(rows.flat_A, rows.owner, rotation)
    u = exact.solve_csr(nom_b[0], A, rows.flat_b, rows.offsets, bodies.lo, bodies.hi)[0]
    return cfg.model.lower(cfg, u, bodies)


@pytest.mark.parametrize(
    "mixed,scale,gamma",
    [(False, 1.0, 10.0), (True, 1.0, 10.0), (False, 1e-3, 20.0), (True, 1e3, 20.0)],
)
def test_culled_unicycle_filter_equals_all_pairs(mixed, scale, gamma):
    """The search by each agent's radius and its nominal's disk (the QP projects (v, l w)
    onto a box that holds 0: ``rsvo_env.filter.projection_disk``) keeps every row that binds,
    single integrators among the unicycles too, in millimetres and kilometres, up to
    gamma dt = 1."""
    p, th, goals, theta, radii = crowd(300, 4, scale)
    l, v_max = 0.06 * scale, V_MAX * scale
    holo = (np.arange(300) % 3 == 0) if mixed else None
    kw = dict(dynamics="unicycle", lookahead=l, w_max=W_MAX, u_max=v_max, gamma=gamma, dt=0.05)
    culled = SafetyFilter(FilterConfig(**kw))
    every = SafetyFilter(FilterConfig(**kw, neighbor_radius=1e9))  # every pair within 1e9
    bound = 0
    for _ in range(15):
        nom = nominal(p, th, goals, l, v_max)
        if mixed:
            c = np.clip(goals - p, -v_max / 2, v_max / 2)
            nom[holo] = c[holo]
        a = culled.filter(p, nom, theta, headings=th, radii=radii, holonomic=holo)
        b = every.filter(p, nom, theta, headings=th, radii=radii, holonomic=holo)
        assert b.rows.n_pairs == 300 * 299 // 2 > a.rows.n_pairs
        # each action's own unit: (v, w) in the world's speed and W_MAX
        unit = np.array([v_max, W_MAX])
        np.testing.assert_allclose(a.actions / unit, b.actions / unit, rtol=0, atol=1e-12)
        want = every_row(culled, p, th, nom, theta, radii, holo)
        np.testing.assert_allclose(a.actions / unit, want / unit, rtol=0, atol=1e-12)
        bound += int(a.active.sum())
        if mixed:
            p, th = step_mixed(p, th, a.actions, holo, l, 0.05)
        else:
            p, th = unicycle_step(p, th, a.actions, l, 0.05)
    assert bound > 0


def step_mixed(p, th, u, holo, l, dt):
    """One step of a mixed crowd: single integrators (holonomic) and unicycles."""
    p, th = p.copy(), th.copy()
    p[~holo], th[~holo] = unicycle_step(p[~holo], th[~holo], u[~holo], l, dt)
    p[holo] = p[holo] + dt * u[holo]
    return p, th


@pytest.mark.parametrize("n,steps,scale", [(40, 150, 1.0), (300, 60, 1e-3), (300, 60, 1e3)])
def test_mixed_crowds_of_single_integrators_and_unicycles(n, steps, scale):
    """Every other agent a single integrator (holonomic): bodies never overlap, the single
    integrators stay in their box, the unicycles' inputs in their bounds."""
    p, th, goals, theta, radii = crowd(n, n + 1, scale)
    holo = np.arange(n) % 2 == 0
    l, dt = 0.08 * scale, 0.05
    flt = SafetyFilter(
        FilterConfig(
            dynamics="unicycle", lookahead=l, w_max=W_MAX, u_max=V_MAX * scale, gamma=20.0, dt=dt
        )
    )
    I, J = pairs.all_pairs(n)
    worst = np.inf
    for _ in range(steps):
        nom = nominal(p, th, goals, l, V_MAX * scale)
        d = goals - p
        dist = np.linalg.norm(d, axis=1, keepdims=True)
        nom[holo] = (d / np.maximum(dist, 1e-300) * np.minimum(dist, V_MAX * scale))[holo]
        res = flt.filter(p, nom, theta, headings=th, radii=radii, holonomic=holo)
        assert res.feasible.all()
        u = res.actions
        assert (np.abs(u[holo]) <= V_MAX * scale * (1 + 1e-12)).all()
        v, w = inputs_through_the_step(u[~holo], l, dt)
        assert (v >= -1e-12 * scale).all() and (v <= V_MAX * scale * (1 + 1e-12)).all()
        assert (np.abs(w) <= W_MAX * (1 + 1e-12)).all()
        p, th = step_mixed(p, th, u, holo, l, dt)
        gap = np.linalg.norm(p[I] - p[J], axis=1) / (radii[I] + radii[J])
        worst = min(worst, float(gap.min()))
    assert 1.0 - 1e-9 <= worst < 1.5


def test_holonomic_is_checked():
    flt = SafetyFilter(FilterConfig(dynamics="unicycle", lookahead=0.1, w_max=1.0))
    x = np.array([[0.0, 0.0], [5.0, 0.0]])
    with pytest.raises(ValueError, match="holonomic must be bools"):
        flt.filter(x, np.zeros((2, 2)), np.ones(2), headings=np.zeros(2), holonomic=[1, 0])
    with pytest.raises(ValueError, match=r"holonomic has shape \(3,\)"):
        flt.filter(
            x, np.zeros((2, 2)), np.ones(2), headings=np.zeros(2), holonomic=np.zeros(3, bool)
        )
    with pytest.raises(ValueError, match="holonomic is for the unicycle"):
        SafetyFilter(FilterConfig()).filter(
            x, np.zeros((2, 2)), np.ones(2), holonomic=np.zeros(2, bool)
        )


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_simulated_unicycle_crowd_behind_the_filter_never_touches(seed):
    from rsvo_env.dynamics.unicycle import heading_vectors as e

    env = rsvo_env.parallel_env("unicycle_crowd", num_agents=12, dt=0.05, max_steps=600)
    env.reset(seed=seed, options={"theta": np.linspace(0.5, 8.0, 12)})
    sim = env.unwrapped.sim
    p = sim.scenario.params
    I, J = pairs.all_pairs(12)
    moved = 0.0
    while env.agents:
        before = sim.state.positions[0].copy()
        _, _, _, _, info = env.step(env.unwrapped.nominal_actions())
        x = sim.state.positions[0]
        assert np.linalg.norm(x[I] - x[J], axis=1).min() >= p["safety_radius"] * (1 - 1e-9)
        assert all(info[a]["feasible"] and info[a]["cost"] == 0 for a in info)
        u = np.stack([info[a]["u_safe"] for a in env.possible_agents])
        assert (u[:, 0] >= 0).all() and (u[:, 0] <= p["u_max"]).all()
        assert (np.abs(u[:, 1]) <= p["w_max"] * (1 + 1e-12)).all()
        # the axle moves along its heading: a unicycle does not slide sideways
        moved += float(np.linalg.norm(x - before, axis=1).sum())
        h0 = sim.state.headings[0]
        side = np.abs(((x - before) * e(h0 + np.pi / 2)).sum(1))
        assert (side <= np.linalg.norm(x - before, axis=1) * 0.5 + 1e-12).all()
    assert moved > 12 * 5.0
    assert env.unwrapped.episode_metrics["n_collision_steps"] == 0


@pytest.mark.parametrize("n,steps,scale", [(40, 150, 1.0), (200, 60, 1e-3), (200, 60, 1e3)])
def test_unicycles_of_their_own_speed_limit(n, steps, scale):
    """``u_max=(N,)``: each unicycle's forward speed stays within its own v_max,i through every
    step (|w| within w_max), the single integrators of a mixed crowd within their own box, and
    bodies never overlap."""
    p, th, goals, theta, radii = crowd(n, 7 * n, scale)
    rng = np.random.default_rng(n)
    v_max = rng.uniform(0.5, 1.0, n) * V_MAX * scale
    holo = rng.random(n) < 0.3
    l, dt = 0.08 * scale, 0.05
    flt = SafetyFilter(
        FilterConfig(
            dynamics="unicycle", lookahead=l, w_max=W_MAX, u_max=V_MAX * scale, gamma=20.0, dt=dt
        )
    )
    I, J = pairs.all_pairs(n)
    worst, slowed = np.inf, 0
    for _ in range(steps):
        nom = nominal(p, th, goals, l, V_MAX * scale)  # asks for more than some agents may
        d = goals - p
        dist = np.linalg.norm(d, axis=1, keepdims=True)
        nom[holo] = (d / np.maximum(dist, 1e-300) * np.minimum(dist, V_MAX * scale))[holo]
        res = flt.filter(p, nom, theta, headings=th, radii=radii, u_max=v_max, holonomic=holo)
        assert res.feasible.all()
        u = res.actions
        assert (np.abs(u[holo]) <= v_max[holo, None] * (1 + 1e-12)).all()
        v, w = inputs_through_the_step(u[~holo], l, dt)
        assert (v >= -1e-12 * scale).all()
        assert (v <= v_max[~holo] * (1 + 1e-12)).all()
        assert (np.abs(w) <= W_MAX * (1 + 1e-12)).all()
        slowed += int((v.max(axis=0) < 0.999 * V_MAX * scale).sum())
        p, th = step_mixed(p, th, u, holo, l, dt)
        gap = np.linalg.norm(p[I] - p[J], axis=1) / (radii[I] + radii[J])
        worst = min(worst, float(gap.min()))
    assert slowed > 0 and worst >= 1.0 - 1e-9
