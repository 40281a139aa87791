"""QP backends: ``exact`` (batched, numba) and ``reference`` (any qpsolvers solver)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from rsvo_env.qp import exact, reference

__all__ = ["exact", "reference", "solve"]


def solve(
    solver: str,
    nominal: NDArray,
    A: NDArray,
    b: NDArray,
    offsets: NDArray,
    lo: NDArray,
    hi: NDArray,
    **options: Any,
) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.int64], NDArray[np.float64]]:
    """Dispatch rows stored by agent (``A[offsets[i]:offsets[i + 1]]``) to the exact solver
    (``"exact"``) or a qpsolvers backend by name."""
    if solver == "exact":
        return exact.solve_csr(nominal, A, b, offsets, lo, hi)
    return reference.solve_csr(nominal, A, b, offsets, lo, hi, solver=solver, **options)
