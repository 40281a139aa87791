"""The responsibility weights the simulation core keeps for its E envs (paper, Thm. 1).

Up to ``sizes.WEIGHT_MATRIX_MAX_AGENTS`` agents an env, or whenever a callable weighting asks for
one, the core keeps the (E, N, N) matrices of ``responsibility.weight_matrix``. Beyond that a
named weighting needs only the scores: each weight is computed where it is read, by the matrix's own
convention (``pair_omega(theta_i, theta_j)`` above the diagonal, ``1 - W.T`` below), so a crowd of
10,000 holds O(N) weights, not 800 MB.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from rsvo_env.responsibility.pair_weights import Floor, floor_of, weight_floor, weight_matrices
from rsvo_env.responsibility.svo import (
    Weighting,
    min_pair_weight,
    named_weights_and_floor,
    scored_weight,
    smallest_weight,
    symmetric_envs,
    weight_matrix,
)
from rsvo_env.util import sizes

# Agents an env up to which the weight matrix is kept (rsvo_env.util.sizes).


class Weights:
    """Weights of E envs of n agents; ``version`` counts the changes (the core is the writer)."""

    def __init__(self, num_envs: int, n: int) -> None:
        self.n = n
        self.matrix: NDArray[np.float64] | None = (
            np.full((num_envs, n, n), 0.5) if n <= sizes.WEIGHT_MATRIX_MAX_AGENTS else None
        )
        self.omega_min = np.full(num_envs, 0.5)
        self.version = 0
        self._floor: tuple[int, Floor] | None = None

    def update(
        self, envs: Sequence[int] | NDArray[np.integer], theta: NDArray, modes: Sequence[Weighting]
    ) -> None:
        """Envs ``envs`` now have scores ``theta[envs]`` and weighting ``modes[e]`` (the same
        mode for all of them); ``theta`` (E, N) and ``modes`` are the core's, whole."""
        idx = np.asarray(envs, dtype=np.int64)
        mode = modes[int(idx[0])]
        if self.matrix is None and callable(mode):
            # a callable weighting needs its matrix: keep every env's from now on
            self.matrix = weight_matrices(theta, modes)
        if self.matrix is not None:
            # the core's scores are valid: a named mode skips weight_matrix's checks
            th = theta[idx]
            if callable(mode):
                self.matrix[idx] = weight_matrix(th, mode)
                self.omega_min[idx] = smallest_weight(self.matrix[idx])
            else:
                self.matrix[idx], self.omega_min[idx] = named_weights_and_floor(th, mode)
        else:
            self.omega_min[idx] = [min_pair_weight(theta[e], mode) for e in idx]
        self.version += 1

    def update_all(self, theta: NDArray, modes: Sequence[Weighting]) -> None:
        """Every env has new scores (theta actions): one ``update`` per weighting in use."""
        groups: dict[object, list[int]] = {}
        for e, m in enumerate(modes):
            # modes are strings or callables: equal strings group, a callable by identity
            groups.setdefault(m if isinstance(m, str) else id(m), []).append(e)
        for envs in groups.values():
            self.update(envs, theta, modes)

    def env_matrix(self, e: int, theta: NDArray, mode: Weighting) -> NDArray[np.float64]:
        """Env e's (N, N) matrix: the kept one, or computed now from its scores."""
        return self.matrix[e] if self.matrix is not None else weight_matrix(theta, mode)

    def neighbors(
        self,
        theta: NDArray,
        modes: Sequence[Weighting],
        nb: NDArray[np.int64],
        envs: NDArray[np.int64] | None = None,
    ) -> tuple[NDArray[np.float64], bool]:
        """Each agent's weight against each of its listed neighbours ``nb`` (E', N, K, local
        indices) in ``envs`` (None: all), as the observation reads it: the matrices (E', N, N)
        themselves, to be read at the neighbours' indices (``True``; no gathered copy made),
        or, where no matrix is kept, the weights (E', N, K) from the scores, the same numbers
        (``False``)."""
        if self.matrix is not None:
            return (self.matrix if envs is None else self.matrix[envs]), True
        pick = slice(None) if envs is None else envs
        th = theta[pick]
        tj = np.take_along_axis(th[:, None, :], nb, axis=2)
        ti = np.broadcast_to(th[:, :, None], nb.shape)
        above = nb > np.arange(self.n)[None, :, None]
        sym = symmetric_envs(modes)[pick][:, None, None]
        weights = np.where(above, scored_weight(ti, tj, sym), 1.0 - scored_weight(tj, ti, sym))
        return weights, False

    def floor(self, theta: NDArray, modes: Sequence[Weighting]) -> Floor:
        """The floor of the large-N pair search (``rsvo_env.geometry.pairs``), once per change:
        from
        the scores, per score group, when the weighting is named; from the matrix otherwise."""
        if self._floor is not None and self._floor[0] == self.version:
            return self._floor[1]
        if len({str(m) for m in modes}) == 1 and isinstance(modes[0], str):
            floor = floor_of(theta, modes[0], self.matrix)
        elif self.matrix is not None:
            floor = weight_floor(self.matrix)
        else:
            floor = self._floor_by_env(theta, modes)
        self._floor = (self.version, floor)
        return floor

    def _floor_by_env(self, theta: NDArray, modes: Sequence[Weighting]) -> Floor:
        """Envs with different named weightings: each env's floor, padded to the most groups
        (an infinite floor searches nothing)."""
        parts = []
        for e, (t, m) in enumerate(zip(theta, modes, strict=True)):
            parts.append((e, floor_of(t[None], m)))
        K = max(p[0].shape[-1] for _, p in parts)
        floor = np.full((len(parts), self.n, K), np.inf)
        for e, p in parts:
            floor[e, :, : p[0].shape[-1]] = p[0][0]
        group = np.concatenate([p[1] for _, p in parts])
        required = np.concatenate([p[2] + e * self.n for e, p in parts])
        return floor, group, required.reshape(-1, 2)

    def pair_modes(self, modes: Sequence[Weighting]) -> list[Weighting] | None:
        """What the filter needs besides the matrix: each env's named weighting when no matrix
        is kept (the filter then computes each pair's weights from the scores)."""
        return None if self.matrix is not None else list(modes)
