"""The exact solver against the qpsolvers reference (clarabel, daqp) and an LP for the fallback."""

import warnings

import numba
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rsvo_env.qp import exact, reference
from rsvo_env.util import sizes, threads
from tests.support.instances import KINDS, make_batch, make_instance, stack


def _compare(solver: str, K: int, count: int, seed: int, tol: float) -> dict:
    rng = np.random.default_rng(seed)
    instances = make_batch(rng, count, K)
    nominal, A, b, mask, lo, hi = stack(instances)
    u, feasible, _, _ = exact.solve_batch(nominal, A, b, mask, lo, hi)
    worst = 0.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for i, inst in enumerate(instances):
            ur, fr, _ = reference.solve_one(
                inst["nominal"], inst["A"], inst["b"], inst["lo"], inst["hi"], solver
            )
            kind = KINDS[i % len(KINDS)]
            assert fr == feasible[i] == inst["feasible"], (kind, i, fr, feasible[i])
            if fr:
                err = float(np.abs(ur - u[i]).max())
                assert err <= tol, (kind, i, err, inst)
                worst = max(worst, err)
    return {"worst": worst, "infeasible": int((~feasible).sum())}


# 4 x 1250 = 5,000 instances per reference solver, a sixth of them of each kind.
@pytest.mark.parametrize("K", [1, 5, 20, 100])
def test_exact_matches_clarabel(K):
    out = _compare("clarabel", K, 1250, seed=K, tol=1e-6)
    assert out["infeasible"] > 0


@pytest.mark.parametrize("K", [1, 5, 20, 100])
def test_exact_matches_daqp(K):
    out = _compare("daqp", K, 1250, seed=100 + K, tol=1e-8)
    assert out["infeasible"] > 0


@pytest.mark.parametrize("K", [1, 5, 20, 100])
def test_least_violation_matches_lp(K):
    rng = np.random.default_rng(7 + K)
    instances = [make_instance(rng, K, "infeasible") for _ in range(200)]
    # some with many mutually conflicting rows, where the min-max point is interior to the box
    for inst in instances[::2]:
        a = rng.normal(size=(K, 2))
        inst["A"] = a
        inst["b"] = -np.abs(rng.normal(size=K)) - 0.1
    nominal, A, b, mask, lo, hi = stack(instances)
    u, feasible, _, violation = exact.solve_batch(nominal, A, b, mask, lo, hi)
    norms = np.linalg.norm(A, axis=2)
    for i, inst in enumerate(instances):
        _, t_star = reference.least_violation(inst["A"], inst["b"], inst["lo"], inst["hi"])
        if t_star <= 1e-9:
            continue  # the random rows happened to intersect: not an infeasible instance
        assert not feasible[i]
        achieved = np.max((A[i] @ u[i] - b[i]) / norms[i])
        assert violation[i] == pytest.approx(t_star, abs=1e-8)
        assert achieved == pytest.approx(t_star, abs=1e-8)
        assert np.all(u[i] >= lo[i] - 1e-12) and np.all(u[i] <= hi[i] + 1e-12)
        # never the nominal passed through
        assert not np.allclose(u[i], inst["nominal"]) or achieved <= t_star + 1e-8


@settings(max_examples=200, deadline=None)
@given(
    st.integers(min_value=1, max_value=30),
    st.integers(min_value=0, max_value=2**32 - 1),
)
def test_exact_solution_is_feasible_and_optimal(K, seed):
    # KKT in 2-D: feasible, and no feasible direction from u decreases |u - nominal|^2 --
    # checked against a dense sample of feasible points.
    rng = np.random.default_rng(seed)
    inst = make_instance(rng, K, "random")
    nominal, A, b, mask, lo, hi = stack([inst])
    u, feasible, _, _ = exact.solve_batch(nominal, A, b, mask, lo, hi)
    assert feasible[0]
    u = u[0]
    assert np.all(A[0] @ u <= b[0] + 1e-9 * (1 + np.abs(b[0])))
    pts = rng.uniform(lo[0], hi[0], (4000, 2))
    ok = np.all(pts @ A[0].T <= b[0], axis=1)
    d_best = np.min(np.sum((pts[ok] - nominal[0]) ** 2, axis=1), initial=np.inf)
    assert np.sum((u - nominal[0]) ** 2) <= d_best + 1e-9


def test_masked_rows_are_ignored():
    nominal = np.array([[1.0, 0.0]])
    A = np.array([[[1.0, 0.0], [1.0, 0.0]]])
    b = np.array([[0.0, -5.0]])
    mask = np.array([[True, False]])
    u, feasible, active, _ = exact.solve_batch(nominal, A, b, mask, -np.ones(2), np.ones(2))
    np.testing.assert_allclose(u, [[0.0, 0.0]], atol=1e-15)
    assert feasible[0] and active[0] == 1


def test_parallel_batch_equals_serial():
    rng = np.random.default_rng(3)
    instances = make_batch(rng, 2 * sizes.PARALLEL_MIN_PROBLEMS + 10, 8)
    nominal, A, b, mask, lo, hi = stack(instances)
    with threads.using(numba.config.NUMBA_NUM_THREADS):
        assert threads.parallel(len(instances)) == (numba.config.NUMBA_NUM_THREADS > 1)
        big = exact.solve_batch(nominal, A, b, mask, lo, hi)
    small = [
        exact.solve_batch(*(x[i : i + 1] for x in (nominal, A, b, mask, lo, hi)))
        for i in range(0, len(instances), 97)
    ]
    for k, i in enumerate(range(0, len(instances), 97)):
        np.testing.assert_array_equal(big[0][i], small[k][0][0])
        assert big[1][i] == small[k][1][0]
