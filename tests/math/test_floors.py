"""The large-N pair search's floors at any ratio of scores: each floor lies below every weight
it stands for (the rounding bounded, not guessed), the search never needs the (N, N) matrix,
and its memory and pairs follow the agents, not the most extreme personality."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rsvo_env.filter.safety import FilterConfig, SafetyFilter
from rsvo_env.responsibility import pair_weights
from rsvo_env.responsibility.svo import weight_matrix
from rsvo_env.util import sizes
from tests.math.test_culling import all_pairs_actions, crowd, moving


@settings(max_examples=200, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(2, 60),
    st.floats(0.0, 24.0),  # log10 of the ratio of scores, up to 1e24
    st.floats(0.0, 0.3),  # share of theta = 0 agents
)
def test_every_floor_lies_below_the_weights_it_stands_for(seed, n, spread, zeros):
    rng = np.random.default_rng(seed)
    theta = 10.0 ** rng.uniform(-spread / 2, spread / 2, (2, n))
    theta[rng.random((2, n)) < zeros] = 0.0
    floor, group, required = pair_weights.theta_floor(theta, "asymmetric")
    listed = {tuple(p) for p in required.tolist()}
    for e in range(2):
        W = weight_matrix(theta[e])  # the weights the filter uses, by the matrix's convention
        for i in range(n):
            for j in range(n):
                if i == j:
                    continue
                f = floor[e, i, group[e, j]]
                if W[i, j] == 0.0:
                    pair = (e * n + min(i, j), e * n + max(i, j))
                    assert pair in listed or f <= 0.0, (e, i, j)
                else:
                    assert f <= W[i, j], (e, i, j, f, W[i, j], theta[e, i], theta[e, j])


@pytest.mark.parametrize("ratio", [995.7, 1e4, 1e6, 1e9, 1e14])
@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
def test_culled_equals_all_pairs_at_extreme_ratios(ratio, scale):
    """One altruist and one egoist among theta 1..10 (ratio up to 1e14, beyond where the floor
    once gave up or exceeded the true weight by 2e-11): the culled actions are the all-pairs
    ones to 1e-12 of the box, in any units."""
    n = 400
    rng = np.random.default_rng(int(np.log10(ratio) * 7))
    x = crowd(n, 3) * scale
    theta = rng.uniform(1.0, 10.0, n)
    theta[5], theta[17] = 10.0 * ratio**0.5, 1.0 / ratio**0.5
    u = 2.0 * scale
    nominal = rng.uniform(-u, u, (n, 2))
    flt = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=scale, u_max=u, dt=0.01))
    assert n > sizes.ALL_PAIRS_MAX_AGENTS  # the per-agent search, not all pairs
    res = flt.filter(x, nominal, theta)
    want = all_pairs_actions(flt, x, nominal, theta)
    np.testing.assert_allclose(res.actions, want, rtol=0, atol=1e-12 * u)


def footprint(theta, x, monkeypatch):
    """Pairs examined and bytes of the rows and the pair search's floors for one filter call,
    with every (N, N) builder made to fail."""

    def no_matrix(*args, **kwargs):
        raise AssertionError("an (N, N) weight matrix was built")

    monkeypatch.setattr(pair_weights, "weight_matrix", no_matrix)
    monkeypatch.setattr(pair_weights, "weight_floor", no_matrix)
    flt = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=1.0, u_max=2.0, dt=0.01))
    res = flt.filter(x, moving(len(x), 0), theta)
    rows = res.rows
    row_bytes = sum(
        a.nbytes
        for a in (
            rows.flat_A,
            rows.flat_b,
            rows.offsets,
            rows.flat_neighbor,
            rows.flat_h,
            rows.pair_h,
            rows.flat_unrecoverable,
            rows.flat_capped,
        )
    )
    floor = pair_weights.floor_of(theta[None], "asymmetric")
    floor_bytes = sum(a.nbytes for a in floor)
    return rows.n_pairs, row_bytes + floor_bytes, res


def test_extreme_personalities_cost_their_own_rows_only(monkeypatch):
    """10,000 agents, theta 1..10; then one at 1e-7 and one at 100 besides: the search examines
    at most 2x the pairs plus the two agents' own rows (N - 1 each), its memory stays within 2x,
    and no (N, N) matrix is built."""
    n = 10_000
    x = crowd(n, 11)
    theta = np.random.default_rng(11).uniform(1.0, 10.0, n)
    base_pairs, base_bytes, _ = footprint(theta, x, monkeypatch)
    extreme = theta.copy()
    extreme[0], extreme[1] = 1e-7, 100.0
    got_pairs, got_bytes, res = footprint(extreme, x, monkeypatch)
    assert got_pairs <= 2 * base_pairs + 2 * (n - 1), (got_pairs, base_pairs)
    assert got_bytes <= 2 * base_bytes, (got_bytes, base_bytes)
    assert res.feasible.all()


def test_a_reused_filter_searches_with_the_radii_of_the_scores_and_bodies_in_force():
    """The search radii are kept from call to call while the scores and bodies stay; new ones
    give new radii. An altruist 10 m behind an egoist it runs toward must slow down (its row
    binds from about 28 m against theta 10 : 1), which a filter still searching with the radii
    of equal scores (1.7 m) would miss."""
    grid = np.stack(np.meshgrid(np.arange(20.0), np.arange(20.0)), -1).reshape(-1, 2) * 5.0
    x = np.concatenate([grid, [[200.0, 0.0], [210.0, 0.0]]])  # 402 agents: the per-agent search
    nominal = np.zeros_like(x)
    nominal[-2] = (2.0, 0.0)  # the altruist heads for the egoist
    flt = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=1.0, u_max=2.0))
    equal = np.ones(len(x))
    spread = equal.copy()
    spread[-2] = 10.0
    for theta, radii in [
        (equal, None),
        (spread, None),
        (spread, np.full(len(x), 0.6)),
        (equal, None),
        (spread, None),
    ]:
        got = flt.filter(x, nominal, theta, radii=radii).actions
        want = SafetyFilter(flt.config).filter(x, nominal, theta, radii=radii).actions
        np.testing.assert_array_equal(got, want)
        slows = theta[-2] == 10.0
        assert (got[-2, 0] < 1.9) == slows, (theta[-2], radii is None, got[-2])
