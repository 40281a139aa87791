"""How close each body comes to touching another body or an obstacle, as a ratio: agent i's
``contact_i = min(min_j |x_i - x_j| / (r_i + r_j), min_o dist(x_i, S_o) / (r_i + rho_o))``.

``contact < 1`` is an overlap; a collision is ``contact < 1 - 1e-9`` (the relative round-off
margin of ``rsvo_env.sim.metrics``), the same test in any units. For identical bodies without
obstacles it is the nearest distance over the safety radius.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from rsvo_env.geometry.obstacles import nearest_points
from rsvo_env.util import grid
from rsvo_env.util.neighbors import nearest_neighbors


def contact(
    positions: NDArray, radii: NDArray, capsules: NDArray | None = None
) -> NDArray[np.float64]:
    """(E, N) each agent's contact ratio (module docstring); ``positions`` (E, N, 2), ``radii``
    (N,) body radii, ``capsules`` (E, O, 5) or None."""
    E, n = positions.shape[:2]
    out = np.full((E, n), np.inf)
    if n >= 2 and np.all(radii == radii[0]):  # identical bodies: the nearest distance
        out = grid.nearest_distance(positions) / (2.0 * radii[0])
    elif n >= 2:
        d, nb = nearest_neighbors(positions, 1)
        r_max = float(radii.max())
        # the agent with the smallest ratio is within d1 (r_i + r_max) / (r_i + r_nb) of i
        bound = d[..., 0] * (radii + r_max) / (radii + radii[nb[..., 0]]) * (1.0 + 1e-12)
        I, J = grid.pairs_within_radii(positions, bound[..., None], np.zeros((E, n), np.int64))
        flat = positions.reshape(-1, 2)
        ri, rj = radii[I % n], radii[J % n]
        ratio = np.linalg.norm(flat[I] - flat[J], axis=-1) / (ri + rj)
        agents = out.reshape(-1)
        np.minimum.at(agents, I, ratio)
        np.minimum.at(agents, J, ratio)
    if capsules is not None and capsules.shape[-2] > 0:
        c = nearest_points(positions, capsules)  # (E, N, O, 2)
        dist = np.linalg.norm(positions[..., None, :] - c, axis=-1)
        ratio = dist / (radii[:, None] + capsules[:, None, :, 4])
        out = np.minimum(out, ratio.min(axis=-1))
    return out
