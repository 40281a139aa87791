"""R-ORCA's jam routing (``rsvo_env/control/rorca/route.py``) against a brute-force reading of
its rule, in any unit; the goal rule on its own clock (``Rules.goal_held``); the right-hand
rule's hold (``rh_hold``)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rsvo_env.control import rorca
from rsvo_env.control.rorca import route as rorca_route
from rsvo_env.control.rorca.route import (
    CROWDED,
    LOOK,
    PROBE,
    SLOW,
    TURN_COST,
    TURNS,
)
from rsvo_env.envs.vector import BatchedEnv
from tests.support.crowd_runs import run_to_goals


def reference(x, v, g, at_goal, pref, scale, speed):
    """The rule of the module docstring, one agent and one heading at a time, every count a
    scan of every agent."""
    out = np.array(pref, dtype=np.float64, copy=True)
    stuck = ~at_goal & (np.einsum("...i,...i->...", v, v) < (SLOW * speed) ** 2)
    for e in range(x.shape[0]):
        if stuck[e].sum() < CROWDED:
            continue
        pts = x[e, stuck[e]]
        for i in range(x.shape[1]):
            d = g[e, i] - x[e, i]
            dist = np.sqrt(d @ d)
            if at_goal[e, i] or dist <= LOOK * scale:
                continue
            u = d / dist

            def count(t, u=u, i=i, e=e, pts=pts):
                c, s = np.cos(np.deg2rad(t)), np.sin(np.deg2rad(t))
                h = np.array([c * u[0] - s * u[1], s * u[0] + c * u[1]])
                p = x[e, i] + LOOK * scale * h
                q = pts - p
                return int((np.einsum("ij,ij->i", q, q) <= (PROBE * scale) ** 2).sum())

            if count(0.0) < CROWDED:
                continue
            costs = [count(t) + TURN_COST * abs(t) for t in TURNS]
            t = np.deg2rad(TURNS[int(np.argmin(costs))])
            c, s = np.cos(t), np.sin(t)
            px, py = pref[e, i]
            out[e, i] = (c * px - s * py, s * px + c * py)
    return out


def knot_scene(rng, E, n, spread, unit=1.0):
    """Envs of ``n`` agents, a knot of stuck ones in the middle and the rest around it, goals
    across the square."""
    x = rng.uniform(-spread, spread, (E, n, 2))
    x[:, : n // 2] *= 0.2  # the knot
    v = rng.normal(0.0, 1.0, (E, n, 2))
    v[:, : n // 2] *= 0.05
    g = rng.uniform(-spread, spread, (E, n, 2))
    at_goal = rng.uniform(size=(E, n)) < 0.1
    pref = rng.normal(0.0, 1.0, (E, n, 2))
    return x * unit, v * unit, g * unit, at_goal, pref * unit


@settings(deadline=None, max_examples=30)  # the first example compiles the kernel
@given(seed=st.integers(0, 2**31), n=st.integers(2, 120), spread=st.floats(3.0, 80.0))
def test_routed_is_the_rule_scanned_by_brute_force(seed, n, spread):
    x, v, g, at_goal, pref = knot_scene(np.random.default_rng(seed), 3, n, spread)
    got = rorca_route.routed(x, v, g, at_goal, pref, 1.0, 2.0)
    np.testing.assert_allclose(got, reference(x, v, g, at_goal, pref, 1.0, 2.0), atol=1e-12)


@pytest.mark.parametrize("unit", [1e-3, 1.0, 1e3])
def test_routing_reads_the_same_in_any_unit(unit):
    """Every length in safety radii: the same scene in millimetres or kilometres turns the
    same agents by the same angles (the outputs scale with the unit), and some do turn."""
    rng = np.random.default_rng(7)
    x, v, g, at_goal, pref = knot_scene(rng, 2, 400, 30.0)
    base = rorca_route.routed(x, v, g, at_goal, pref, 1.0, 2.0)
    scaled = rorca_route.routed(
        x * unit, v * unit, g * unit, at_goal, pref * unit, unit, 2.0 * unit
    )
    np.testing.assert_allclose(scaled / unit, base, rtol=1e-9, atol=1e-12)
    turned = np.linalg.norm(base - pref, axis=-1) > 1e-9
    assert 0 < turned.sum() < turned.size


def test_a_thin_spread_of_stuck_agents_widens_the_cells_and_counts_the_same():
    """Stuck agents kilometres apart (the grid would need millions of cells of the probe's
    width): the cells widen, and the counts are still the brute-force ones."""
    rng = np.random.default_rng(3)
    x, v, g, at_goal, pref = knot_scene(rng, 1, 60, 10.0)
    x[0, -3:] = [[5e4, 5e4], [-5e4, 3e4], [2e4, -6e4]]
    v[0, -3:] = 0.0
    got = rorca_route.routed(x, v, g, at_goal, pref, 1.0, 2.0)
    np.testing.assert_allclose(got, reference(x, v, g, at_goal, pref, 1.0, 2.0), atol=1e-12)


def test_fewer_stuck_agents_than_crowded_turn_no_one():
    rng = np.random.default_rng(5)
    x, v, g, at_goal, pref = knot_scene(rng, 1, 40, 10.0)
    v[:] = 5.0  # every agent fast
    v[0, : CROWDED - 1] = 0.0
    assert np.array_equal(rorca_route.routed(x, v, g, at_goal, pref, 1.0, 2.0), pref)


def test_an_agent_heading_into_a_knot_turns_right_around_it():
    """A knot straight ahead of an agent, the ground to both sides clear: it turns, to the right
    (the first of the equal headings), and an agent at its goal or within the look-ahead of it
    does not."""
    knot = np.array([[6.0 + dx, dy] for dx in (-1.0, 0.0, 1.0) for dy in (-1.0, 0.0, 1.0)])
    movers = np.array([[0.0, 0.0], [0.0, 20.0], [3.0, -20.0]])
    x = np.concatenate([knot, movers])[None]
    v = np.zeros_like(x)
    v[0, 9:] = (2.0, 0.0)
    g = x.copy()
    g[0, 9] = (30.0, 0.0)  # through the knot
    g[0, 10] = (30.0, 20.0)  # clear ground
    g[0, 11] = (8.0, -20.0)  # within the look-ahead
    at_goal = np.zeros((1, 12), bool)
    pref = np.zeros_like(x)
    pref[0, 9:] = (2.0, 0.0)
    out = rorca_route.routed(x, v, g, at_goal, pref, 1.0, 2.0)
    # 60 degrees right: 30 degrees off, the probe still reaches the knot's edge; the knot is
    # symmetric, so left would count the same
    assert np.allclose(out[0, 9], (2.0 * np.cos(np.pi / 3), -2.0 * np.sin(np.pi / 3)))
    assert np.array_equal(out[0, 10:], pref[0, 10:])


def test_the_goal_rule_on_its_own_clock_is_the_stages_rule_when_the_clocks_agree():
    """``goal_held`` equal to ``held`` gives the stages' own goal rule bit for bit, dense and
    grid; another clock gives other velocities (the rule reads it)."""
    for n in (40, 300):
        env = BatchedEnv(
            "crowd",
            num_envs=2,
            num_agents=n,
            theta_range=(1.0, 10.0),
            dt=0.05,
            gamma=20.0,
            max_steps=400,
        )
        env.reset(seed=2)
        for _ in range(120):
            env.step(env.nominal_actions())
        s, sc = env.sim.state, env.sim.scenario
        held = np.random.default_rng(0).uniform(size=s.at_goal.shape) < 0.5
        args = (
            s.positions,
            s.velocities,
            s.goals - 0.2 * (s.goals - s.positions),
            sc.radii * 1.05,
            s.theta,
            s.weighting,
            2.0,
            0.05,
        )

        runs = [
            rorca.rorca_velocities(
                *args,
                rules=rorca.Rules(
                    parked=s.at_goal,
                    goals=s.goals,
                    held=held,
                    omega=s.omega,
                    reach=3.0,
                    goal_held=goal_held,
                ),
            )
            for goal_held in (None, held, ~held)
        ]
        assert np.array_equal(runs[0], runs[1])
        assert not np.array_equal(runs[0], runs[2])


@pytest.mark.parametrize("kwargs,field", [({"rorca_goal_hold": -1.0}, "rorca_goal_hold"),
                                          ({"rorca_goal_hold": float("nan")}, "rorca_goal_hold"),
                                          ({"rorca_route": "yes"}, "rorca_route"),
                                          ({"rorca_route": 1}, "rorca_route"),
                                          ({"rh_hold": -0.1}, "rh_hold"),
                                          ({"rh_hold": float("inf")}, "rh_hold"),
                                          ({"rh_hold": "5"}, "rh_hold")])  # fmt: skip
def test_routing_and_the_holds_refuse_bad_values_by_name(kwargs, field):
    with pytest.raises(ValueError, match=field):
        BatchedEnv("crowd", num_envs=1, num_agents=4, **kwargs)


@pytest.mark.parametrize("fused", [True, False])
def test_the_right_hand_rule_with_a_hold_turns_only_agents_stalled_that_long(fused):
    """``rh_hold``: the agents the rule turns are those it fires for (a neighbour within the
    trigger, short of the goal) that have come no closer to their goals for the hold, on both
    after-step paths; and some are turned, some held back."""
    env = BatchedEnv(
        "crowd",
        num_envs=2,
        num_agents=30,
        theta_range=(1.0, 10.0),
        dt=0.05,
        gamma=20.0,
        rh_hold=0.5,
        max_steps=2000,
        rorca_route=False,
    )
    env.sim.post_step_in_one_call = fused
    env.reset(seed=4)
    sc, s = env.sim.scenario, env.sim.state
    turned = held_back = 0
    for _ in range(200):
        clock = s.no_progress.copy()  # the clock the after-step reads, before it ticks
        env.step(env.nominal_actions())
        fires = (s.nearest < sc.rh_trigger) & ~s.at_goal
        assert np.array_equal(s.rh_active, fires & (clock * 0.05 >= 0.5))
        turned += int(s.rh_active.sum())
        held_back += int((fires & ~s.rh_active).sum())
    assert turned > 0 and held_back > 0


@pytest.mark.parametrize("seed", range(3))
def test_a_routed_crowd_of_400_finishes_behind_the_filter_with_no_collision(seed):
    """The crowd's defaults route R-ORCA around knots (its rules set for crowds of 1,000 and
    10,000), behind the unchanged filter: every agent arrives, no pair ever closer than
    R (1 - 1e-9), and the routing turns some agents' preferred velocities on the way."""
    env = BatchedEnv(
        "crowd",
        num_envs=1,
        safety_filter=True,
        num_agents=400,
        max_steps=3000,
        dt=0.05,
        gamma=20.0,
        theta_range=(1.0, 10.0),
    )
    env.reset(seed=seed)
    sc, s = env.sim.scenario, env.sim.state
    turned = []

    def count_turned(env):
        straight = sc.move_to_goal(s, True, sc.speed)
        routed = rorca_route.routed(
            s.positions, s.velocities, s.goals, s.at_goal, straight, 1.0, sc.speed
        )
        turned.append(int((np.abs(routed - straight).max(axis=-1) > 0).sum()))

    reached = run_to_goals(env, 3000, count_turned)
    assert reached.all(), f"{int((~reached).sum())} agents never reached their goals"
    assert sum(turned) > 0


@pytest.mark.parametrize("nominal,route,hold", [("rorca", True, rorca_route.RH_HOLD),
                                                ("rorca", False, 0.0),
                                                ("move_to_goal", True, 0.0)])  # fmt: skip
def test_the_right_hand_rules_hold_defaults_to_the_controllers_own(nominal, route, hold):
    """Routed R-ORCA's right-hand rule waits RH_HOLD seconds of no progress (its last resort);
    unrouted R-ORCA's and the paper's move-to-goal's fires at once; a given hold wins."""
    kw = dict(num_envs=1, num_agents=4, nominal=nominal, rorca_route=route)
    assert BatchedEnv("crowd", **kw).sim.scenario.params["rh_hold"] == hold
    assert BatchedEnv("crowd", rh_hold=0.25, **kw).sim.scenario.params["rh_hold"] == 0.25


@pytest.mark.parametrize("model", ["double_integrator", "unicycle"])
def test_routed_crowds_of_every_model_finish_with_no_collision(model):
    """The crowd routes every model by default. The routing reads the model's steered points
    and their velocities (the unicycle's look-ahead points): routed crowds of 100 double
    integrators and unicycles arrive, every pair at least R (1 - 1e-9) apart."""
    env = BatchedEnv(
        "crowd",
        num_envs=1,
        num_agents=100,
        dynamics=model,
        dt=0.05,
        gamma=20.0,
        theta_range=(1.0, 10.0),
        max_steps=3000,
    )
    env.reset(seed=0)
    reached = run_to_goals(env, 3000)
    assert reached.all(), f"{int((~reached).sum())} agents never reached their goals"


@pytest.mark.parametrize("change,field", [
    ({"goals": np.zeros((1, 5, 2))}, "goals"),
    ({"at_goal": np.zeros((1, 4), bool)}, "at_goal"),
    ({"scale": 0.0}, "scale"),
    ({"scale": float("nan")}, "scale"),
    ({"speed": True}, "speed"),
    ({"speed": -2.0}, "speed"),
])  # fmt: skip
def test_routed_refuses_bad_input_by_name(change, field):
    x = np.zeros((1, 6, 2))
    kw = {
        "positions": x,
        "velocities": x,
        "goals": x,
        "at_goal": np.zeros((1, 6), bool),
        "preferred": x,
        "scale": 1.0,
        "speed": 2.0,
        **change,
    }
    with pytest.raises(ValueError, match=field):
        rorca_route.routed(**kw)
