"""The k-nearest-neighbour kernels against a stable sort, ties and scales included."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rsvo_env.util import sizes
from rsvo_env.util.neighbors import _knn_inserted, _knn_lanes, _knn_ranked, nearest_neighbors


def reference(x: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """(E, N, k) distances and indices by numpy's stable sort of the squared distances."""
    rel = x[:, :, None, :] - x[:, None, :, :]
    d2 = rel[..., 0] * rel[..., 0] + rel[..., 1] * rel[..., 1]
    n = x.shape[1]
    d2[:, np.arange(n), np.arange(n)] = np.inf
    idx = np.argsort(d2, axis=-1, kind="stable")[..., :k]
    return np.sqrt(np.take_along_axis(d2, idx, axis=-1)), idx


def crowd(seed: int, e: int, n: int, scale: float, lattice: bool) -> np.ndarray:
    """Positions with many exact ties: a lattice (equal distances everywhere) or random points
    of which a third repeat another agent's position."""
    rng = np.random.default_rng(seed)
    if lattice:
        side = int(np.ceil(np.sqrt(n)))
        grid = np.stack(np.meshgrid(np.arange(side), np.arange(side)), -1).reshape(-1, 2)
        x = np.stack([grid[rng.permutation(side * side)[:n]] for _ in range(e)]).astype(float)
    else:
        x = rng.uniform(-1.0, 1.0, (e, n, 2)) * np.sqrt(n)
        copies = rng.integers(0, n, (e, n // 3))
        x[:, : n // 3] = np.take_along_axis(x, copies[..., None], axis=1)
    return x * scale


def run(kernel, x: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    dist = np.empty((*x.shape[:2], k))
    idx = np.empty((*x.shape[:2], k), dtype=np.int64)
    kernel(x, k, dist, idx)
    return dist, idx


@settings(max_examples=150, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    e=st.integers(1, 4),
    n=st.integers(2, sizes.ALL_PAIRS_MAX_AGENTS),
    k_share=st.floats(0.0, 1.0),
    scale=st.sampled_from([1e-6, 1e-3, 1.0, 1e3, 1e6]),
    lattice=st.booleans(),
)
def test_both_kernels_are_the_stable_sort(seed, e, n, k_share, scale, lattice):
    x = crowd(seed, e, n, scale, lattice)
    k = 1 + int(k_share * (n - 2))
    want_d, want_i = reference(x, k)
    for kernel in (_knn_inserted, _knn_ranked, _knn_lanes):
        d, i = run(kernel, x, k)
        np.testing.assert_array_equal(i, want_i, err_msg=kernel.__name__)
        np.testing.assert_array_equal(d, want_d, err_msg=kernel.__name__)


@pytest.mark.parametrize(
    "e", [1, 3, 16, 17, sizes.KNN_LANES_MIN_ENVS - 1, sizes.KNN_LANES_MIN_ENVS]
)
@pytest.mark.parametrize("n", [2, 7, 8, 16, 32, 33, 64])
@pytest.mark.parametrize("k", [1, 3, 4, 6])
def test_the_public_query_is_the_stable_sort_either_side_of_the_thresholds(e, n, k):
    """nearest_neighbors picks a kernel by the batch's shape (measured thresholds); whichever
    runs, the answer is the stable sort, bit for bit."""
    k = min(k, n - 1)
    x = crowd(n * k + e, e, n, 1.0, lattice=(n % 2 == 0))
    d, i = nearest_neighbors(x, k)
    want_d, want_i = reference(x, k)
    np.testing.assert_array_equal(i, want_i)
    np.testing.assert_array_equal(d, want_d)
