"""The weights a filter reads for its scenes' scores (paper, Thm. 1), kept for the last scores:
a simulator calls with the same scores step after step, so the (E, N, N) matrices and the
weights' floor of a named weighting are built once per change of scores."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rsvo_env.responsibility import pair_weights
from rsvo_env.responsibility.pair_weights import Floor
from rsvo_env.responsibility.svo import Weighting, weight_matrix


class KeptWeights:
    """The configured ``weighting``'s matrices and floor of the last scores; a callable
    weighting is asked every time."""

    def __init__(self, weighting: Weighting) -> None:
        self.weighting = weighting
        # per kind ("floor", "matrix"): the last scores and what the weighting gave for them
        self.kept: dict[str, tuple[NDArray, Any]] = {}

    def floor(self, theta: NDArray, omega: NDArray | None) -> Floor:
        """``pair_weights.weight_floor`` of the weights in force: of a caller's matrices
        ``omega`` where given, else from the scores ``theta`` (E, N) alone (O(N) memory) for a
        named weighting."""
        if omega is not None:  # a caller's matrix, whatever the configured mode says
            return pair_weights.weight_floor(omega)
        return self.of_scores("floor", theta, pair_weights.floor_of)

    def matrix(self, theta: NDArray, weighting: Sequence[Weighting] | None) -> NDArray:
        """(E, N, N) weight matrices of ``theta`` (E, N): each env's named ``weighting``, or
        the configured one."""
        if weighting is not None:
            return np.stack([weight_matrix(t, m) for t, m in zip(theta, weighting, strict=True)])
        return self.of_scores("matrix", theta, weight_matrix)

    def of_scores(self, kind: str, theta: NDArray, build: Callable) -> Any:
        """``build(theta, weighting)`` of the configured weighting, kept for the last scores of
        each ``kind`` when the weighting is named."""
        if callable(self.weighting):
            return build(theta, self.weighting)
        last = self.kept.get(kind)
        if last is None or not np.array_equal(last[0], theta):
            last = self.kept[kind] = (theta.copy(), build(theta, self.weighting))
        return last[1]
