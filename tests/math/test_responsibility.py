import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rsvo_env.responsibility.svo import r_svo, responsibility_weight, weight_matrix

scores = st.floats(min_value=0.0, max_value=1e6, allow_nan=False, allow_infinity=False)


@settings(max_examples=300, deadline=None)
@given(scores, scores)
def test_phi_bounds_and_complement(ti, tj):
    phi_i, phi_j = r_svo(ti, tj), r_svo(tj, ti)
    assert 0.0 <= phi_i <= np.pi / 2
    assert phi_i + phi_j == pytest.approx(np.pi / 2, abs=1e-12)


@settings(max_examples=300, deadline=None)
@given(scores, scores)
def test_weights_sum_to_one(ti, tj):
    assert responsibility_weight(ti, tj) + responsibility_weight(tj, ti) == pytest.approx(
        1.0, abs=1e-12
    )


@settings(max_examples=100, deadline=None)
@given(scores)
def test_equal_theta_is_prosocial(t):
    assert r_svo(t, t) == pytest.approx(np.pi / 4, abs=1e-15)
    assert responsibility_weight(t, t) == pytest.approx(0.5, abs=1e-15)


@settings(max_examples=300, deadline=None)
@given(scores, scores, st.floats(min_value=1e-3, max_value=1e6))
def test_more_egoistic_means_larger_omega(ti, delta, tj):
    # a smaller theta_i (more egoistic) never lowers omega_i (up to the round-off of cos, a few
    # 1e-17 when delta is below theta_i's own precision), and strictly raises it
    w_ego = responsibility_weight(ti, tj)
    w_alt = responsibility_weight(ti + delta, tj)
    assert w_ego >= w_alt - 1e-15
    if delta > 1e-6 * (ti + tj) and 1e-6 < w_ego < 1.0:
        assert w_ego > w_alt


def test_limits():
    assert responsibility_weight(0.0, 0.0) == 0.5
    assert r_svo(0.0, 0.0) == pytest.approx(np.pi / 4)
    assert responsibility_weight(0.0, 3.0) == 1.0  # pure egoist: the pair's whole budget
    assert responsibility_weight(3.0, 0.0) == 0.0
    assert responsibility_weight(1.0, 4.0) == pytest.approx(np.cos(np.pi / 10) ** 2)


def test_broadcasting():
    th = np.array([1.0, 2.0, 3.0])
    w = responsibility_weight(th[:, None], th[None, :])
    assert w.shape == (3, 3)
    np.testing.assert_allclose(w + w.T, 1.0, atol=1e-12)


@pytest.mark.parametrize("bad", [-1.0, np.nan, np.inf, -np.inf])
def test_bad_theta_names_index(bad):
    th = [1.0, 2.0, bad, 4.0]
    with pytest.raises(ValueError, match=r"theta\[2\].*agent 2"):
        weight_matrix(th)
    with pytest.raises(ValueError, match=r"theta_i"):
        r_svo(bad, 1.0)


@pytest.mark.parametrize("mode", ["asymmetric", "symmetric"])
def test_weight_matrix_pairs_sum_to_one(mode):
    rng = np.random.default_rng(0)
    th = rng.uniform(0, 10, 12)
    th[3] = 0.0
    W = weight_matrix(th, mode)
    off = ~np.eye(12, dtype=bool)
    np.testing.assert_allclose((W + W.T)[off], 1.0, atol=1e-15)
    assert np.all(np.diag(W) == 0)
    if mode == "symmetric":
        assert np.all(W[off] == 0.5)
    else:
        assert W[0, 1] == pytest.approx(responsibility_weight(th[0], th[1]), abs=1e-15)


def test_weight_matrix_callable_is_validated():
    good = weight_matrix([1.0, 2.0], lambda t: [[0.0, 0.3], [0.7, 0.0]])
    assert good[0, 1] == 0.3
    with pytest.raises(ValueError, match=r"omega\[0, 1\] \+ omega\[1, 0\] = 1"):
        weight_matrix([1.0, 2.0], lambda t: [[0.0, 0.3], [0.3, 0.0]])
    with pytest.raises(ValueError, match=r"omega\[0, 1\] = -0.5"):
        weight_matrix([1.0, 2.0], lambda t: [[0.0, -0.5], [1.5, 0.0]])
    with pytest.raises(ValueError, match="unknown"):
        weight_matrix([1.0, 2.0], "selfish")


# every magnitude a float holds, subnormals and the largest finite included
any_score = st.floats(min_value=0.0, max_value=np.finfo(float).max, allow_infinity=False)


@settings(max_examples=400, deadline=None)
@given(any_score, any_score)
def test_weights_sum_to_one_at_any_magnitude(ti, tj):
    """No overflow: ``theta_i + theta_j`` of two huge scores is inf, which once gave 1.0 both
    ways (a pair summing to 2)."""
    wi, wj = responsibility_weight(ti, tj), responsibility_weight(tj, ti)
    assert 0.0 <= wi <= 1.0 and 0.0 <= wj <= 1.0
    assert wi + wj == pytest.approx(1.0, abs=1e-12)
    assert r_svo(ti, tj) + r_svo(tj, ti) == pytest.approx(np.pi / 2, abs=1e-12)


@pytest.mark.parametrize("t", [1e308, np.finfo(float).max, 1e-320, 5e-324, 1.0, 1e200])
def test_equal_scores_give_one_half_at_any_magnitude(t):
    assert responsibility_weight(t, t) == 0.5
    assert r_svo(t, t) == np.pi / 4
    W = weight_matrix(np.array([t, t, t]))
    np.testing.assert_array_equal(W[~np.eye(3, dtype=bool)], 0.5)
    assert responsibility_weight(1e308, 1e307) + responsibility_weight(1e307, 1e308) == (
        pytest.approx(1.0, abs=1e-15)
    )


@settings(max_examples=200, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(2, 30),
    st.floats(-300.0, 308.0),  # log10 of the scores' scale, up to sums that overflow
    st.floats(0.0, 0.5),  # share of theta = 0 agents
)
def test_pair_weights_from_scores_are_the_weight_matrix_entries(seed, n, scale, zeros):
    """The compiled pair weights (``pair_weights.scored_pairs``, the filter's large-N path) are the
    weight matrix's entries bit for bit, in every env's weighting, at any scale of scores."""
    from rsvo_env.geometry import pairs
    from rsvo_env.responsibility import pair_weights

    rng = np.random.default_rng(seed)
    theta = rng.uniform(0.0, 1.0, (3, n)) * 10.0**scale
    theta[rng.random((3, n)) < zeros] = 0.0
    theta[1, 1] = theta[1, 0]  # equal scores give exactly 1/2
    theta[2, :2] = 1.5e308, 1.7e308  # a sum that overflows
    I, J = pairs.all_pairs(n, 3)
    modes = ["asymmetric", "symmetric", "asymmetric"]
    got = pair_weights.weights_of(theta, modes, I, J)
    W = np.stack([weight_matrix(t, m) for t, m in zip(theta, modes, strict=True)])
    np.testing.assert_array_equal(got, pair_weights.omega_pairs(W.reshape(3 * n, n), I, J, n))
    # and the numbers of Def. 1 as numpy computes them, an independent route
    from rsvo_env.responsibility.svo import scored_weight

    th = theta.reshape(-1)
    w = scored_weight(th[I], th[J], np.array([m == "symmetric" for m in modes])[I // n])
    np.testing.assert_array_equal(got, np.stack([w, 1.0 - w], axis=1))


@settings(max_examples=200, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 4),
    st.integers(2, 40),
    st.floats(-300.0, 308.0),
    st.floats(0.0, 0.5),
)
def test_compiled_weight_matrices_are_the_named_ones(seed, k, n, scale, zeros):
    """The compiled matrices and floors (``named_weights_and_floor``, which resets and
    ``weight_matrix`` use) are Def. 1's numbers as numpy computes them, bit for bit, at any
    scale of scores: ``pair_omega`` above the diagonal, 1 minus its transpose below."""
    from rsvo_env.responsibility.svo import named_weights, named_weights_and_floor, pair_omega

    rng = np.random.default_rng(seed)
    theta = rng.uniform(0.0, 1.0, (k, n)) * 10.0**scale
    theta[rng.random((k, n)) < zeros] = 0.0
    theta[0, :2] = 1.5e308, 1.7e308  # a sum that overflows
    upper = np.triu(np.ones((n, n), dtype=bool), 1)
    formula = pair_omega(theta[:, :, None], theta[:, None, :])
    want = np.where(upper, formula, 1.0 - np.swapaxes(formula, -1, -2))
    want[:, np.arange(n), np.arange(n)] = 0.0
    w, floor = named_weights_and_floor(theta, "asymmetric")
    np.testing.assert_array_equal(w, want)
    np.testing.assert_array_equal(named_weights(theta, "asymmetric"), want)
    off = ~np.eye(n, dtype=bool)
    np.testing.assert_array_equal(floor, np.where(off, want, np.inf).min(axis=(1, 2)))
