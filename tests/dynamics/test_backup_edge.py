"""The backup barrier at its edge (issue 43, findings 1 and 2): rounding must never turn a safe
state into an infeasible QP, at extreme speeds nor for a resting cluster within rounding of
contact. Each test failed before the slack at the backup took Lemma 1's closed form and the
settled band covered the solver's own allowance (``docs/double_integrator.md``)."""

import numpy as np
import pytest

import rsvo_env
from rsvo_env.dynamics import double_integrator_step
from rsvo_env.dynamics.barriers import stopping
from rsvo_env.filter.safety import SafetyFilter
from tests.dynamics.test_backup_barrier import config
from tests.support.backup_states import pair_h


@pytest.mark.parametrize("speed_over_c_dt", [1e2, 1e6, 1e8, 1e9, 1e10])
@pytest.mark.parametrize("dt, gamma_dt", [(0.01, 1.0), (0.1, 0.5), (0.1, 1.0), (1.0, 0.5)])
def test_head_on_pairs_at_h_zero_stay_feasible_at_any_speed(speed_over_c_dt, dt, gamma_dt):
    """Head-on pairs at h = 0 closing at up to 1e10 c dt: the slack at the backup exceeds 0 by
    c dt^2 / 2 while a difference of reaches rounds at eps s^2 / c, so the rows keep Lemma 1's
    terms in closed form. Every QP feasible; h+ >= (1 - gamma dt) h to 1e-12 of the scene."""
    c, I, J = np.array([1.0, 2.0]), np.array([0]), np.array([1])
    s = speed_over_c_dt * c * dt
    v = np.array([[s[0], 0.0], [-s[1], 0.0]])
    radii = np.array([0.5, 0.7])
    L = stopping.stopping_reach(s, c, dt)
    gap = radii.sum() + L.sum()
    p = np.array([[-0.5 * gap, 0.0], [0.5 * gap, 0.0]])
    flt = SafetyFilter(config(dt, gamma_dt))
    res = flt.filter(
        p, np.array([[1.0, 0.0], [-2.0, 0.0]]), [1.0, 3.0], velocities=v, radii=radii, u_max=c
    )
    assert res.feasible.all()
    h0 = pair_h(p, v, radii, c, dt, I, J)[0]
    p1, v1 = double_integrator_step(p, v, res.actions, dt)
    h1 = pair_h(p1, v1, radii, c, dt, I, J)[0]
    assert h1 >= (1 - gamma_dt) * h0 - 1e-12 * gap


def hexagon(rings=2):
    """A hexagonal patch of 1 + 3 rings (rings + 1) unit-spaced lattice points, 19 for 2 rings."""
    pts = [np.zeros(2)]
    for ring in range(1, rings + 1):
        for k in range(6):
            corner = ring * np.array([np.cos(np.pi / 3 * k), np.sin(np.pi / 3 * k)])
            side = np.array([np.cos(np.pi / 3 * (k + 2)), np.sin(np.pi / 3 * (k + 2))])
            pts += [corner + m * side for m in range(ring)]
    return np.array(pts)


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
@pytest.mark.parametrize("squeeze", [0.0, 1e-13, 1e-11, 1e-10])
def test_a_resting_cluster_within_rounding_of_contact_is_feasible_and_holds(scale, squeeze):
    """19 bodies of radius 1 at rest, each touching its neighbours to within ``squeeze`` of
    their distance (rounding: not a collision by the project's test, 1 - 1e-9), gamma dt = 1:
    whatever the nominal, every QP is feasible and no pair comes closer. An agent at rest can
    only keep its h, so reading a rounding below 0 as a deficit would make its QP infeasible."""
    rng = np.random.default_rng(int(squeeze * 1e13) + 3)
    n, dt = 19, 0.5
    p = hexagon() * 2.0 * (1.0 - squeeze) * scale
    v, radii, a = np.zeros((n, 2)), np.full(n, scale), np.full(n, scale)
    I, J = np.triu_indices(n, 1)
    flt = SafetyFilter(config(dt, 1.0, scale))
    h0 = pair_h(p, v, radii, a, dt, I, J)[0]
    for _ in range(20):
        res = flt.filter(
            p,
            rng.uniform(-1, 1, (n, 2)) * scale,
            rng.uniform(0, 10, n),
            velocities=v,
            radii=radii,
            u_max=a,
        )
        assert res.feasible.all()
        p1, v1 = double_integrator_step(p, v, res.actions, dt)
        h1 = pair_h(p1, v1, radii, a, dt, I, J)[0]
        assert (h1 >= np.minimum(h0, 0.0) - 1e-12 * scale).all()


def test_a_packed_hexagon_driven_by_its_scene_controller_stays_feasible():
    """The custom scene of 19 touching double integrators at rest, radius 1, dt 0.5, gamma 2
    (gamma dt = 1), driven by the scene's own scripted controller toward shuffled goals across
    the cluster: no infeasible agent-step, no contact."""
    starts = hexagon() * 2.0 * (1.0 + 1e-15)  # the lattice's rounding kept outside contact
    infeasible, cost = 0, 0.0
    for seed in range(6):
        rng = np.random.default_rng(seed)
        goals = starts[rng.permutation(19)] * 1.5 + rng.uniform(-0.5, 0.5, (19, 2))
        env = rsvo_env.parallel_env(
            "custom",
            starts=starts,
            goals=goals,
            radii=np.ones(19),
            dynamics="double_integrator",
            dt=0.5,
            gamma=2.0,
            max_steps=120,
        )
        env.reset(seed=seed, options={"theta": rng.uniform(1, 10, 19)})
        while env.agents:
            *_, infos = env.step(env.unwrapped.nominal_actions())
            infeasible += sum(not i["feasible"] for i in infos.values())
            cost += sum(i["cost"] for i in infos.values())
    assert infeasible == 0 and cost == 0.0
