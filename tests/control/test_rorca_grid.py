"""R-ORCA's grid stage (``rsvo_env/control/rorca/grid.py``, envs beyond 64 agents) against the
pair-by-pair assembly of ``test_rorca`` on crowds its cells find hard."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rsvo_env.control import rorca
from tests.control.test_rorca import reference_velocities


@settings(deadline=None, max_examples=10)
@given(st.integers(65, 150), st.integers(0, 2**32 - 1), st.sampled_from([1e-3, 1.0, 1e4]),
       st.sampled_from([0.0, 1.0, 3.0]))  # fmt: skip
def test_the_grid_stage_equals_the_assembly_in_clusters_far_apart_and_at_any_scale(
    n, seed, unit, reach
):
    """The grid stage's cells coarsen over a crowd whose bounding box is mostly empty (two
    clusters and a lone agent far apart, some agents on one point): the same velocities as the
    pair-by-pair assembly, bit for bit, in any units, at any reach of the goal rule."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(0, 1.2 * np.sqrt(n // 2), (n, 2))
    x[n // 2 :] += 1e4
    x[-1] = (-3e4, 5e3)
    x[1] = x[0]  # two agents on one point
    x *= unit
    v, pref = rng.uniform(-1, 1, (n, 2)) * unit, rng.uniform(-2, 2, (n, 2)) * unit
    goals = x + rng.uniform(-1.5, 1.5, (n, 2)) * unit
    radii = rng.uniform(0.3, 0.6, n) * unit
    theta = rng.uniform(1, 10, n)
    parked, held = rng.random(n) < 0.2, rng.random(n) < 0.5
    expected = reference_velocities(
        x, v, pref, radii, theta, 2.0 * unit, 0.05, 2.0, parked, goals, held, 10, reach
    )
    got = rorca.rorca_velocities(
        x[None],
        v[None],
        pref[None],
        radii,
        theta[None],
        ["asymmetric"],
        2.0 * unit,
        0.05,
        2.0,
        rules=rorca.Rules(parked[None], goals[None], held[None], reach=reach),
    )[0]
    assert np.array_equal(got, expected)
