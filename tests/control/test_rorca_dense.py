"""R-ORCA's stage for envs of at most sizes.ALL_PAIRS_MAX_AGENTS agents
(``rsvo_env/control/rorca/dense.py``): each agent reads the others of its env in place and its
weights from the env's matrix, and the velocities are bit for bit those of the grid stage
(``rsvo_env/control/rorca/grid.py``, the one for larger envs) run on the same envs; the
simulation core hands it its own matrices, kept current."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rsvo_env.control import rorca
from rsvo_env.control.rorca import grid as rorca_grid
from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.responsibility import pair_weights
from rsvo_env.responsibility.svo import symmetric_envs, weight_matrix


def grid_stage(x, v, pref, radii, theta, modes, K, parked, goals, held, u_max=2.0, dt=0.05):
    """The grid stage (``rsvo_env/control/rorca/grid.py``, envs beyond 64 agents) on envs of
    any size, with the rules and the cut rorca_velocities gives it, its weights from the
    scores (1/2 in the symmetric envs) or the matrices where a weighting is a callable."""
    E, n = x.shape[:2]
    M = E * n
    f = lambda a: np.ascontiguousarray(a, dtype=np.float64).reshape(M, -1)  # noqa: E731
    xf, vf, pf, gf = f(x), f(v), f(pref), f(goals)
    r = f(np.broadcast_to(radii, (E, n))).reshape(M)
    omega = pair_weights.weight_matrices(theta, modes) if any(map(callable, modes)) else None
    rules = (parked.reshape(M), held.reshape(M), True, rorca.GOAL_REACH, held.reshape(M))
    out = rorca_grid.stage(
        n,
        (xf, vf, gf, pf, r),
        theta,
        symmetric_envs(modes),
        omega,
        rules,
        (K, u_max, 2.0, dt, 10.0 * float(r.max())),
    )
    return out.reshape(E, n, 2)


def swapped(theta):
    """A callable weighting: the matrix of the scores in reverse order's roles."""
    return weight_matrix(theta[::-1].copy())[::-1, ::-1].copy()


@settings(deadline=None, max_examples=40)
@given(st.integers(2, 64), st.integers(1, 3), st.integers(0, 2**32 - 1),
       st.sampled_from([-1, 3, 10]), st.booleans())  # fmt: skip
def test_the_dense_stage_equals_the_grid_stage_bit_for_bit(n, E, seed, K, lattice):
    """Mixed weightings (asymmetric, symmetric, a callable) across envs, agents parked, held
    and overlapping; on a lattice distances tie and the nearest K break ties by list order."""
    rng = np.random.default_rng(seed)
    side = np.sqrt(n) * 1.3
    if lattice:
        x = np.floor(rng.uniform(0, side, (E, n, 2)))
        x += 1e-3 * np.arange(n)[None, :, None]  # distinct points, many equal distances
    else:
        x = rng.uniform(0, side, (E, n, 2))
    v, pref = rng.uniform(-1, 1, (E, n, 2)), rng.uniform(-2, 2, (E, n, 2))
    goals = x + rng.uniform(-1.5, 1.5, (E, n, 2))
    radii = rng.uniform(0.3, 0.6, n)
    theta = rng.uniform(1, 10, (E, n))
    modes = ["asymmetric", "symmetric", swapped][:E]
    parked, held = rng.random((E, n)) < 0.2, rng.random((E, n)) < 0.5
    expected = grid_stage(x, v, pref, radii, theta, modes, K, parked, goals, held)
    args = (x, v, pref, radii, theta, modes, 2.0, 0.05, 2.0)
    K = None if K < 0 else K
    W = pair_weights.weight_matrices(theta, modes)
    computed, given_matrices = (
        rorca.rorca_velocities(*args, max_neighbors=K, rules=rorca.Rules(parked, goals, held, m))
        for m in (None, W)
    )
    assert np.array_equal(computed, expected)
    assert np.array_equal(given_matrices, expected)


@settings(deadline=None, max_examples=10)
@given(st.integers(65, 200), st.integers(1, 2), st.integers(0, 2**32 - 1))
def test_beyond_64_agents_the_matrices_given_are_gathered_into_the_same_weights(n, E, seed):
    """The grid stage reads ``Rules.omega`` too (the kept pairs' entries): the velocities are
    those of the weights computed from the scores, bit for bit."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(0, np.sqrt(n) * 1.3, (E, n, 2))
    v, pref = rng.uniform(-1, 1, (E, n, 2)), rng.uniform(-2, 2, (E, n, 2))
    goals, theta = x + rng.uniform(-1.5, 1.5, (E, n, 2)), rng.uniform(1, 10, (E, n))
    parked, held = rng.random((E, n)) < 0.2, rng.random((E, n)) < 0.5
    modes = ["asymmetric", swapped][:E]
    args = (x, v, pref, 0.5, theta, modes, 2.0, 0.05)
    computed, given_matrices = (
        rorca.rorca_velocities(*args, rules=rorca.Rules(parked, goals, held, m))
        for m in (None, pair_weights.weight_matrices(theta, modes))
    )
    assert np.array_equal(computed, given_matrices)


@pytest.mark.parametrize("dynamics", ["single_integrator", "unicycle"])
def test_the_core_hands_r_orca_its_own_matrices_and_keeps_them_current(dynamics):
    """``State.omega`` is the core's weight matrix itself, rewritten in place by a reset and by
    set_weighting; the scripted controller gives the same actions as with matrices computed
    from the scores."""
    env = BatchedEnv("crowd", num_envs=3, num_agents=16, dynamics=dynamics, theta_range=(1.0, 10.0))
    sim = env.sim
    for round_ in range(3):
        env.reset(seed=[round_, 10 + round_, 20 + round_])
        if round_ == 2:
            env.set_weighting("symmetric")
        s = sim.state
        assert s.omega is sim.weights.matrix
        for e in range(3):
            assert np.array_equal(s.omega[e], weight_matrix(s.theta[e], s.weighting[e]))
        for _ in range(40):
            env.step(env.nominal_actions())
        sc = sim.scenario
        preferred = sc.move_to_goal(s, True, sc.speed)
        with_core = sc.steer(s, preferred)
        s.omega = None  # the same state, the matrices computed from the scores
        try:
            computed = sc.steer(s, preferred)
        finally:
            s.omega = sim.weights.matrix
        assert np.array_equal(with_core, computed)


@settings(deadline=None)
@given(cut=st.floats(1e-150, 1e150), scale=st.floats(0.0, 4.0), ulps=st.integers(-4, 4))
def test_within_decides_the_cut_as_the_square_root_does(cut, scale, ulps):
    """``rorca_agent.within``: ``d2 <= within(cut)`` is ``sqrt(d2) <= cut`` exactly (the stages
    test the cut without a square root), at the threshold and a few ulps either side of
    ``cut^2``, in any units."""
    from rsvo_env.control.rorca.agent import within

    T = within(cut)
    d2s = [scale * cut * cut, cut * cut, T]
    for d2 in list(d2s):
        for _ in range(abs(ulps)):
            d2 = np.nextafter(d2, np.inf if ulps > 0 else 0.0)
        d2s.append(d2)
    for d2 in d2s:
        assert (d2 <= T) == (np.sqrt(d2) <= cut), (cut, d2)
    assert within(np.inf) == np.inf
