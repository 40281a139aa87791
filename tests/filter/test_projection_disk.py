"""Culling by the nominal (``rsvo_env.filter.projection_disk``, docs/math.md "Culling by the
nominal"):
the single-integrator solution lies in the disk with diameter [0, nominal] while no row has
b < 0, so the rows that cannot bind there, and the pairs beyond the radius of min(|nominal|,
|U|), are dropped; the actions stay those of every row of every pair, in any units, with
agents already too close (which keep their box's radius and rows), nominals outside the box,
at its corners, zero and huge."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rsvo_env.dynamics import single_integrator
from rsvo_env.filter import projection_disk
from rsvo_env.filter.safety import FilterConfig, SafetyFilter
from rsvo_env.geometry import pairs
from rsvo_env.qp import exact
from rsvo_env.responsibility import pair_weights
from rsvo_env.scenarios import Crowd
from rsvo_env.util import grid, sizes


def every_row(flt, x, nominal, theta, cull=False):
    """The definition: the QP with every row of every pair, nothing culled (with ``cull``, the
    rows that cannot bind in the box culled: the filter before culling by the nominal)."""
    cfg = flt.config
    I, J = pairs.all_pairs(len(x))
    w = flt.pair_weights(theta, None, I, J)
    rows = single_integrator.single_integrator_rows(
        x, w, I, J, cfg.gamma, cfg.safety_radius, cfg.lo, cfg.hi, cull=cull
    )
    return exact.solve_csr(nominal, rows.flat_A, rows.flat_b, rows.offsets, cfg.lo, cfg.hi)


def nominals(rng, n, u, kind):
    """Nominal actions of a kind: inside the box, far outside it, at its corners, zero, or
    a mix with tiny ones."""
    if kind == "inside":
        return rng.uniform(-u, u, (n, 2))
    if kind == "outside":
        return rng.uniform(-1, 1, (n, 2)) * u * 1e3
    if kind == "corners":
        return rng.choice([-1.0, 1.0], (n, 2)) * u * rng.choice([1.0, 1.0 + 1e-12, 3.0], (n, 1))
    if kind == "zero":
        return np.zeros((n, 2))
    out = rng.uniform(-u, u, (n, 2))
    out[rng.uniform(size=n) < 0.3] *= 1e-12
    return out


def packed(n, rng, scale, overlap):
    """n agents in a box about 3 safe distances a side per agent (they interact), some pairs
    closer than R when ``overlap`` (those agents' sets may not hold 0)."""
    side = np.sqrt(n) * 1.6
    x = rng.uniform(0, side, (n, 2))
    if overlap:
        k = max(1, n // 8)
        who = rng.choice(n, 2 * k, replace=False)
        x[who[k:]] = x[who[:k]] + rng.uniform(-0.6, 0.6, (k, 2))
    return x * scale


@settings(max_examples=150, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(2, 40),
    log_scale=st.sampled_from([-3.0, 0.0, 3.0]),
    kind=st.sampled_from(["inside", "outside", "corners", "zero", "mixed"]),
    overlap=st.booleans(),
    zeros=st.booleans(),
)
def test_the_culled_filter_is_the_qp_of_every_row(seed, n, log_scale, kind, overlap, zeros):
    """The compiled dense pass and the general path (all pairs, rows kept) against the QP of
    every row, to 1e-12 of the box; the flags agree."""
    rng = np.random.default_rng(seed)
    scale = 10.0**log_scale
    u = 2.0 * scale
    x = packed(n, rng, scale, overlap)
    theta = rng.uniform(0.1, 10.0, n)
    if zeros:
        theta[rng.uniform(size=n) < 0.2] = 0.0
    nominal = nominals(rng, n, u, kind)
    flt = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=scale, u_max=u, dt=0.05))
    want, want_ok = every_row(flt, x, nominal, theta)[:2]
    fast = flt.filter(x, nominal, theta)
    general = flt.apply(x[None], nominal[None], theta[None], with_rows=True)
    for res in (fast, general.squeeze()):
        np.testing.assert_array_equal(res.feasible, want_ok)
        ok = want_ok
        np.testing.assert_allclose(res.actions[ok], want[ok], rtol=0, atol=1e-12 * u)
    np.testing.assert_array_equal(fast.actions, general.actions[0])
    np.testing.assert_array_equal(fast.n_rows, general.n_rows[0])
    # the solver skips a row its current point satisfies and clamps a new row's point by
    # earlier rows; a dropped row holds on the whole disk, where every such point lies, so it
    # changes no value: bit for bit the actions of the box's culling alone
    np.testing.assert_array_equal(fast.actions, every_row(flt, x, nominal, theta, cull=True)[0])


def crowd(n, seed):
    return Crowd(num_agents=n, spacing_factor=1.0)._spread(np.random.default_rng(seed))


@pytest.mark.parametrize("kind", ["inside", "outside", "corners", "zero", "mixed"])
@pytest.mark.parametrize("too_close", [0, 3, 2 * sizes.EXEMPT_SCAN_MAX_AGENTS])
def test_the_large_crowd_search_keeps_every_row_that_can_bind(kind, too_close):
    """900 agents, theta 1..10 with zeros (the per-agent grid search), some pairs already
    closer than R (a few: each scans its env with its box's radius; many: the grid does):
    the actions are those of every row, and the scene's smallest barrier value is the
    smallest over all pairs, however short the search radii of slow agents."""
    n = 900
    rng = np.random.default_rng(too_close + len(kind))
    x = crowd(n, 5)
    if too_close:
        who = rng.choice(n, 2 * too_close, replace=False)
        x[who[too_close:]] = x[who[:too_close]] + rng.uniform(-0.5, 0.5, (too_close, 2))
    theta = rng.uniform(1.0, 10.0, n)
    theta[:2] = 0.0
    nominal = nominals(rng, n, 2.0, kind)
    flt = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=1.0, u_max=2.0, dt=0.05))
    assert n > sizes.COMPILED_FILTER_MAX_AGENTS
    res = flt.filter(x, nominal, theta)
    want, ok = every_row(flt, x, nominal, theta)[:2]
    np.testing.assert_array_equal(res.feasible, ok)
    np.testing.assert_allclose(res.actions[ok], want[ok], rtol=0, atol=1e-12 * 2.0)
    np.testing.assert_array_equal(res.actions, every_row(flt, x, nominal, theta, cull=True)[0])
    I, J = pairs.all_pairs(n)
    h = ((x[I] - x[J]) ** 2).sum(axis=1) - 1.0
    np.testing.assert_allclose(res.min_h, h.min(), rtol=1e-12, atol=1e-12)
    # the filter carries the agents found exempt to its next call (a jam holds): whatever it
    # carries, a wrong guess included, the actions are those of a fresh filter
    for other in (x, np.roll(x, 7, axis=0), crowd(n, 6)):
        got = flt.filter(other, nominal, theta)
        fresh = SafetyFilter(flt.config).filter(other, nominal, theta)
        np.testing.assert_array_equal(got.actions, fresh.actions)
        np.testing.assert_allclose(got.min_h, fresh.min_h, rtol=1e-12, atol=0)


def test_slow_and_receding_agents_examine_fewer_pairs_and_keep_fewer_rows():
    """What the disk buys, and that it is the nominal that decides: at rest, agents examine
    only the pairs closer than their radius plus a hair; at full speed, fewer than the box's
    radius gives (|nominal| = u_max < |U| = u_max sqrt 2), and keep fewer rows."""
    n = 2000
    x = crowd(n, 7)
    theta = np.random.default_rng(7).uniform(1, 10, n)
    flt = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=1.0, u_max=2.0, dt=0.05))
    rest = flt.filter(x, np.zeros_like(x), theta).rows
    inward = -2.0 * x / np.linalg.norm(x, axis=1, keepdims=True)
    moving = flt.filter(x, inward, theta).rows
    I, J = pairs.all_pairs(n)
    d = np.linalg.norm(x[I] - x[J], axis=1)
    floor = pair_weights.theta_floor(theta[None], "asymmetric")
    box_radii = pairs.agent_radii(floor[0], 10.0, np.full((1, n), 2 * 2**0.5), np.ones((1, n)))
    box_pairs = len(grid.pairs_within_radii(x[None], box_radii, floor[1])[0])
    assert rest.n_pairs <= int((d <= 1.0 + 1e-6).sum()) + 1
    assert moving.n_pairs < 0.75 * box_pairs
    assert len(moving.flat_b) > 0 and len(rest.flat_b) == 0


def test_agent_radii_are_the_sensing_radius_of_each_floor():
    """The compiled radii, bit for bit the root of docs/math.md (widened by 1e-9), 0 where a
    floor has no member, infinite where it is 0 or below."""
    rng = np.random.default_rng(3)
    floor = rng.uniform(0.0, 1.0, (2, 50, 4))
    floor[0, 0] = (np.inf, 0.0, -1e-17, 1e-300)
    speed = rng.uniform(0.0, 3.0, (2, 50))
    reach = rng.uniform(0.1, 4.0, (2, 50))
    got = pairs.agent_radii(floor, 10.0, speed, reach)
    u, R = speed[..., None], reach[..., None]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        wg = floor * 10.0
        want = (u + np.sqrt(u * u + (wg * R) ** 2)) / wg * (1.0 + 1e-9)
    want = np.where(floor > 0, want, np.inf)
    want = np.where(np.isfinite(floor), want, 0.0)
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("many", [False, True])
def test_the_box_pairs_of_exempt_agents_join_the_search(many):
    """The pairs of the exempt agents within their box's radius, joined to a sorted list:
    sorted, each once, by the env scan (few) and the grid (many) alike."""
    rng = np.random.default_rng(int(many))
    E, n, K = 2, 120, 3
    x = rng.uniform(0, 20, (E, n, 2))
    radius = rng.uniform(0.5, 4.0, (E, n, K))
    group = rng.integers(0, K, (E, n))
    exempt = rng.uniform(size=E * n) < (0.5 if many else 0.02)
    assert (exempt.sum() > sizes.EXEMPT_SCAN_MAX_AGENTS) == many
    I0, J0 = grid.pairs_within_radii(x, rng.uniform(0.0, 2.0, (E, n, K)), group)
    I, J = projection_disk.box_pairs(x, radius, group, exempt, I0, J0)
    want = set(zip(I0.tolist(), J0.tolist(), strict=True))
    for a in np.flatnonzero(exempt):
        e, i = divmod(a, n)
        for j in range(n):
            d2 = ((x[e, i] - x[e, j]) ** 2).sum()
            if j != i and d2 <= radius[e, i, group[e, j]] ** 2:
                want.add((e * n + min(i, j), e * n + max(i, j)))
    np.testing.assert_array_equal(np.stack([I, J], 1), np.array(sorted(want)))
    assert n > sizes.ALL_PAIRS_MAX_AGENTS
