"""Static obstacles (circles and walls) in the filter: crowds driven straight through random
fields never let a body touch an obstacle or another body, in millimetres as in kilometres;
culling the obstacle rows changes no action; the reference solver agrees; bad obstacles are
refused by name."""

import numpy as np
import pytest

from rsvo_env.filter.safety import FilterConfig, SafetyFilter
from rsvo_env.geometry import pairs
from rsvo_env.geometry.bodies import Bodies
from rsvo_env.geometry.obstacles import Obstacles, single_integrator_obstacle_rows
from rsvo_env.qp import solve as solvers
from rsvo_env.qp.rows import with_obstacles


def field(seed: int, n: int, scale: float = 1.0):
    """A 40 x 40 field: 12 circles (r 0.5-2) and 6 walls (length 3-8, thickness 0.1-0.4) in the
    middle band; n agents of radius 0.2-0.6 start on the left, goals on the right (every path
    crosses the band)."""
    rng = np.random.default_rng(seed)
    circles = np.c_[rng.uniform(12, 28, (12, 2)) * [1, 1], rng.uniform(0.5, 2.0, 12)]
    mid = rng.uniform(12, 28, (6, 2))
    ang = rng.uniform(0, np.pi, 6)
    half = rng.uniform(1.5, 4.0, 6)[:, None] * np.c_[np.cos(ang), np.sin(ang)]
    walls = np.stack([mid - half, mid + half], axis=1)
    thickness = rng.uniform(0.1, 0.4, 6)
    radii = rng.uniform(0.2, 0.6, n)
    ys = np.linspace(1, 39, n)
    starts = np.c_[1.0 + 3.0 * (np.arange(n) % 3), ys]  # three columns: no overlap at n <= 90
    goals = np.c_[np.full(n, 38.0), ys[rng.permutation(n)]]
    obstacles = Obstacles.of(circles * scale, walls * scale, thickness * scale)
    return obstacles, starts * scale, goals * scale, radii * scale


def straight_nominal(x, goals, u):
    d = goals - x
    dist = np.linalg.norm(d, axis=1, keepdims=True)
    return d / np.maximum(dist, 1e-300) * np.minimum(dist, u)


def body_gap(x, radii):
    I, J = pairs.all_pairs(len(x))
    return float((np.linalg.norm(x[I] - x[J], axis=1) - radii[I] - radii[J]).min())


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
@pytest.mark.parametrize("seed,n", [(0, 20), (1, 40), (2, 90)])
@pytest.mark.parametrize("gamma", [10.0, 20.0])  # gamma dt = 0.5 and the edge, 1
def test_no_body_penetrates_an_obstacle_or_another_body(seed, n, scale, gamma):
    obstacles, x, goals, radii = field(seed, n, scale)
    assert (obstacles.clearance(x, radii) > 0).all() and body_gap(x, radii) > 0
    dt, u = 0.05, 2.0 * scale
    flt = SafetyFilter(FilterConfig(gamma=gamma, u_max=u, dt=dt))
    theta = np.random.default_rng(seed).uniform(0, 5, n)
    closest = np.inf
    for _ in range(300):
        res = flt.filter(x, straight_nominal(x, goals, u), theta, radii=radii, obstacles=obstacles)
        assert res.feasible.all(), "a QP was infeasible in the safe set"
        x = x + dt * res.actions
        clear = obstacles.clearance(x, radii)
        closest = min(closest, float(clear.min()) / scale)
        assert (clear >= -1e-9 * radii).all(), "a body entered an obstacle"
        assert body_gap(x, radii) >= -1e-9 * 2 * radii.max()
    assert closest < 0.05, "the crowd never reached an obstacle: the test tested nothing"


def test_culling_the_obstacle_rows_changes_no_action():
    obstacles, x, goals, radii = field(3, 40)
    cfg = FilterConfig(gamma=10.0, u_max=2.0, dt=0.05)
    flt = SafetyFilter(cfg)
    theta = np.ones(40)
    for _ in range(120):
        nominal = straight_nominal(x, goals, 2.0)
        res = flt.filter(x, nominal, theta, radii=radii, obstacles=obstacles)
        bodies = Bodies.of(cfg, 1, 40, radii[None])
        I, J = pairs.all_pairs(40)
        rows = cfg.model.rows(cfg, x, None, flt.pair_weights(theta, None, I, J), I, J, bodies)
        full = single_integrator_obstacle_rows(
            x, bodies.radii, obstacles.capsules[None], 40, 10.0, bodies.lo, bodies.hi, False
        )
        rows = with_obstacles(rows, *full[:5])
        ref = solvers.solve(
            "exact", nominal, rows.flat_A, rows.flat_b, rows.offsets, bodies.lo, bodies.hi
        )[0]
        np.testing.assert_array_equal(res.actions, ref)
        x = x + 0.05 * res.actions
    assert (res.rows.flat_neighbor < 0).any(), "no obstacle row ever bound"


def test_reference_solver_agrees_with_obstacles():
    obstacles, x, goals, radii = field(4, 20)
    exact = SafetyFilter(FilterConfig(gamma=10.0, u_max=2.0, dt=0.05))
    ref = SafetyFilter(FilterConfig(gamma=10.0, u_max=2.0, dt=0.05, solver="clarabel"))
    for _ in range(150):
        nominal = straight_nominal(x, goals, 2.0)
        a = exact.filter(x, nominal, np.ones(20), radii=radii, obstacles=obstacles)
        b = ref.filter(x, nominal, np.ones(20), radii=radii, obstacles=obstacles)
        np.testing.assert_allclose(a.actions, b.actions, atol=2e-6)
        x = x + 0.05 * a.actions


def test_an_agent_stops_at_a_wall_and_a_circle():
    obstacles = Obstacles.of(
        circles=[(0.0, 0.0, 1.0)], walls=[((2.0, -1.0), (2.0, 1.0))], thickness=0.2
    )
    flt = SafetyFilter(FilterConfig(gamma=10.0, dt=0.05))
    x = np.array([[-3.0, 0.0], [5.0, 0.0]])
    for _ in range(200):
        res = flt.filter(x, np.array([[2.0, 0.0], [-2.0, 0.0]]), np.ones(2), obstacles=obstacles)
        x = x + 0.05 * res.actions
    # body radius 1/2 (safety_radius 1): against the circle's 1 and the wall's half thickness
    np.testing.assert_allclose(x, [[-1.5, 0.0], [2.6, 0.0]], atol=1e-6)
    assert res.min_h == pytest.approx(0.0, abs=1e-9)
    assert set(res.rows.flat_neighbor) == {-1, -2}  # obstacle o is neighbour -1 - o


def test_obstacles_per_env_in_a_batch():
    one = Obstacles.of(circles=[(0.0, 0.0, 1.0)])
    two = Obstacles.of(circles=[(10.0, 0.0, 1.0)])
    both = Obstacles(np.stack([one.capsules, two.capsules]))
    x = np.array([[[-3.0, 0.0]], [[7.0, 0.0]]])
    flt = SafetyFilter(FilterConfig(gamma=10.0, dt=0.05))
    for _ in range(200):
        x = (
            x
            + 0.05
            * flt.filter(x, np.full((2, 1, 2), [2.0, 0.0]), np.ones((2, 1)), obstacles=both).actions
        )
    np.testing.assert_allclose(x[:, 0, 0], [-1.5, 8.5], atol=1e-6)


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"circles": [(0.0, 0.0, -1.0)]}, r"circles\[0\] has radius -1.0"),
        ({"circles": [(0.0, np.nan, 1.0)]}, r"circles\[0\] = \[0.0, nan, 1.0\] is not finite"),
        ({"circles": [(0.0, 1.0)]}, r"each entry is \(x, y, r\)"),
        ({"circles": [("a", 0, 1)]}, r"circles must be real numbers"),
        ({"walls": [((0, 0), (1, 1))], "thickness": -0.1}, r"thickness\[0\] = -0.1 .*wall 0"),
        ({"walls": [((0, 0), (1, 1))], "thickness": [0.1, 0.2]}, r"one per wall"),
        ({"walls": [((0, 0), (1, np.inf))]}, r"walls\[0\] .* is not finite"),
    ],
)
def test_bad_obstacles_are_refused_by_name(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Obstacles.of(**kwargs)


def test_obstacles_refused_where_not_supported():
    flt = SafetyFilter(FilterConfig())
    x = np.array([[0.0, 0.0], [5.0, 0.0]])
    with pytest.raises(ValueError, match="pass an Obstacles"):
        flt.filter(x, np.zeros((2, 2)), np.ones(2), obstacles=[(0, 0, 1)])


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
@pytest.mark.parametrize("dt,gamma", [(0.05, 2.0), (0.05, 20.0), (0.1, 10.0), (0.02, 50.0)])
@pytest.mark.parametrize("speed_share", [0.0, 0.5, 0.99])
def test_a_double_integrator_brakes_before_a_circle_from_any_stoppable_speed(
    scale, dt, gamma, speed_share
):
    """Head on, full throttle into the circle, from a speed the box can stop before it (h >= 0):
    never inside, every QP feasible, and it ends up at the circle."""
    from rsvo_env.dynamics import double_integrator_step

    a_max, rho = 1.0 * scale, 1.0 * scale
    obstacles = Obstacles.of(circles=[(0.0, 0.0, rho)])
    flt = SafetyFilter(
        FilterConfig(
            dynamics="double_integrator",
            barrier="braking",
            u_max=a_max,
            gamma=gamma,
            safety_radius=scale,
            dt=dt,
        )
    )
    Ds = 0.5 * scale + rho
    room = 3.0 * scale
    v0 = np.sqrt(2 * a_max * room) * speed_share  # h = room - v0^2 / (2 a_max) >= 0
    x, v = np.array([[-(Ds + room), 0.0]]), np.array([[v0, 0.0]])
    step = 0.05 if dt is None else dt
    for _ in range(int(30 / step)):
        res = flt.filter(x, np.array([[a_max, 0.0]]), np.ones(1), v, obstacles=obstacles)
        assert res.feasible.all()
        x, v = double_integrator_step(x, v, res.actions, step)
        assert np.linalg.norm(x[0]) >= Ds * (1 - 1e-9)
    # it did come up to the circle (the filter let it approach, and held it there)
    assert np.linalg.norm(x[0]) < Ds + 0.2 * room


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_double_integrator_through_a_field_of_circles_never_enters_one(seed):
    """One vehicle at a time, full speed through circles spaced farther apart than it needs to
    stop (one active obstacle at a time: the case the proof covers), from many starts."""
    from rsvo_env.dynamics import double_integrator_step

    rng = np.random.default_rng(seed)
    grid = np.stack(np.meshgrid([10.0, 20.0, 30.0], [8.0, 18.0, 28.0]), -1).reshape(-1, 2)
    circles = np.c_[grid + rng.uniform(-1, 1, grid.shape), rng.uniform(0.5, 1.5, len(grid))]
    obstacles = Obstacles.of(circles=circles)
    flt = SafetyFilter(
        FilterConfig(dynamics="double_integrator", barrier="braking", u_max=1.0, gamma=2.0, dt=0.05)
    )
    near = np.inf
    for y in np.linspace(4.0, 32.0, 8):
        x, v = np.array([[0.0, y]]), np.zeros((1, 2))
        goal = np.array([[40.0, 36.0 - y]])
        for _ in range(700):
            nominal = 2.0 * (straight_nominal(x, goal, 2.0) - v)
            res = flt.filter(x, nominal, np.ones(1), v, obstacles=obstacles)
            assert res.feasible.all()
            x, v = double_integrator_step(x, v, res.actions, 0.05)
            clear = float(obstacles.clearance(x, 0.5).min())
            assert clear >= -1e-9
            near = min(near, clear)
    assert near < 0.2, "no vehicle came near a circle"


def test_walls_are_refused_for_the_double_integrators_braking_barrier():
    di = SafetyFilter(FilterConfig(dynamics="double_integrator", barrier="braking", u_max=2.0))
    x = np.array([[0.0, 0.0], [5.0, 0.0]])
    with pytest.raises(ValueError, match="walls are not available for the double_integrator"):
        di.filter(
            x,
            np.zeros((2, 2)),
            np.ones(2),
            np.zeros((2, 2)),
            obstacles=Obstacles.of(walls=[((2.0, -1.0), (2.0, 1.0))]),
        )
    tight = SafetyFilter(
        FilterConfig(
            dynamics="double_integrator",
            barrier="braking",
            u_max=2.0,
            dt=0.4,
            gamma=2.0,
            safety_radius=1.0,
        )
    )
    with pytest.raises(ValueError, match="sampled-data guarantee"):
        tight.filter(
            x,
            np.zeros((2, 2)),
            np.ones(2),
            np.zeros((2, 2)),
            obstacles=Obstacles.of(circles=[(2.0, 2.0, 0.01)]),
        )
