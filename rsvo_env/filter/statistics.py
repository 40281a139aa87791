"""Each scene's smallest barrier value ``min h``, the filter's report of how close its closest
pair came to the safe distance (``FilterResult.min_h``)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from rsvo_env.dynamics.model import Dynamics
from rsvo_env.geometry import pairs
from rsvo_env.geometry.bodies import Bodies
from rsvo_env.qp.rows import Rows
from rsvo_env.util.neighbors import nearest_distance


def min_h(
    rows: Rows,
    positions: NDArray,
    I: NDArray,
    dense: bool,
    bodies: Bodies,
    model: Dynamics,
    nearest: NDArray | None = None,
    reach: NDArray | None = None,
    obstacle_h: NDArray | None = None,
) -> NDArray[np.float64]:
    """(E,) smallest barrier value of each scene over the pairs examined; for ``model``s whose
    value must cover every pair (the single integrator beyond the dense size), over all pairs
    (the nearest pair may lie outside the pair search). ``reach`` (E,): the smallest positive
    search radius of each scene; every pair closer than it was examined, so a closer examined
    pair is the scene's nearest. ``obstacle_h`` (E * N,): each agent's smallest barrier value
    against the obstacles, which the scene's value also covers."""
    E, n = positions.shape[:2]
    if obstacle_h is not None:
        h = min_h(rows, positions, I, dense, bodies, model, nearest, reach)
        return np.minimum(h, obstacle_h.reshape(E, n).min(axis=-1))
    if dense:
        if n < 2:
            return np.full(E, np.inf)
        return rows.pair_h.reshape(E, -1).min(axis=-1)
    out = np.full(E, np.inf)
    if len(I):
        # pairs come sorted by I, so each env's pairs are one run
        env = I // n
        starts = np.flatnonzero(np.r_[True, env[1:] != env[:-1]])
        out[env[starts]] = np.minimum.reduceat(rows.pair_h, starts)
    if model.barrier_over_all_pairs():
        # no pair beyond the reach has a smaller barrier than reach^2 - (2 r_max)^2
        R2 = (2.0 * bodies.r_max) ** 2
        if nearest is None and reach is not None and np.all(out <= reach**2 - R2):
            return out
        if bodies.uniform:
            d = (nearest_distance(positions) if nearest is None else nearest).min(axis=-1)
            return np.minimum(out, d**2 - R2)
        return np.minimum(out, nearest_barrier(positions, bodies))
    return out


def nearest_barrier(positions: NDArray, bodies: Bodies) -> NDArray[np.float64]:
    """(E,) the smallest ``|x_i - x_j|^2 - (r_i + r_j)^2`` of each scene over all pairs: the
    pairs within the nearest distance plus twice the largest radius hold it."""
    E, n = positions.shape[:2]
    d = nearest_distance(positions).min(axis=-1)
    reach = float((d + 2.0 * bodies.r_max).max())
    I, J = pairs.candidate_pairs(positions, reach)
    out = np.full(E, np.inf)
    flat = positions.reshape(-1, 2)
    h = ((flat[I] - flat[J]) ** 2).sum(axis=-1) - bodies.pair_distance(I, J) ** 2
    np.minimum.at(out, I // n, h)
    return out
