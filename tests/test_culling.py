"""Per-agent exact culling (single integrator): each agent examines the neighbours within its own
radius, so a few altruists or a theta = 0 agent no longer make every agent examine every pair,
and the actions are those of the all-pairs filter."""

import numpy as np
import pytest

from rsvo_env import barriers, pairs
from rsvo_env.safety import FilterConfig, SafetyFilter
from rsvo_env.scenarios import Crowd
from rsvo_env.solvers import exact


def crowd(n, seed):
    return Crowd(num_agents=n, spacing_factor=1.0)._spread(np.random.default_rng(seed))


def all_pairs_actions(flt, x, nominal, theta):
    cfg = flt.config
    I, J = pairs.all_pairs(len(x))
    w = flt.pair_weights(theta, None, I, J)
    rows = barriers.single_integrator_rows(x, w, I, J, cfg.gamma, cfg.safety_radius, cfg.lo, cfg.hi)
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
    return flt.filter(x, np.zeros_like(x), theta).rows.n_pairs


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
    # ~28 m away, but only the altruists search that far
    spread = np.random.default_rng(7).uniform(1, 10, n)
    assert pairs_examined(spread, x) <= 0.5 * global_radius_pairs(spread, x)
