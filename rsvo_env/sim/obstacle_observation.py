"""What an agent sees of the static obstacles: the ``OBSTACLE_POINTS`` nearest obstacle surface
points, nearest first, each relative to the agent (in its frame), with the body's gap to it and
a present flag. Appended after the neighbours' blocks, in scenes that have obstacles only (the
layout of every other scene is unchanged)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from rsvo_env.geometry.obstacles import nearest_points
from rsvo_env.util.planar import rotate

OBSTACLE_POINTS = 4
# rel_point (2), gap (1), present (1)
OBSTACLE_WIDTH = 4


def count(num_obstacles: int) -> int:
    """How many obstacle blocks an agent observes."""
    return min(num_obstacles, OBSTACLE_POINTS)


def bounds(p: float, reach: float, k: int) -> tuple[list[float], list[float]]:
    """(low, high) of k blocks: points within ``2 p sqrt 2`` (p bounds every position), a gap
    down to ``-reach`` (a body inside an obstacle, without the filter)."""
    far = 2.0 * p * np.sqrt(2.0)
    return [-far, -far, -reach, 0.0] * k, [far, far, far, 1.0] * k


def observe(
    positions: NDArray, radii: NDArray, capsules: NDArray, frame_angle: NDArray | None, k: int
) -> NDArray[np.float64]:
    """(E, N, k * OBSTACLE_WIDTH): for each agent its k nearest obstacles' surface points
    relative to it, the gap ``|x - c| - rho - r_i``, and 1."""
    E, n = positions.shape[:2]
    c = nearest_points(positions, capsules)  # (E, N, O, 2)
    d = c - positions[..., None, :]
    dist = np.linalg.norm(d, axis=-1)
    rho = capsules[:, None, :, 4]
    order = np.argsort(dist - rho, axis=-1, kind="stable")[..., :k]
    d = np.take_along_axis(d, order[..., None], axis=-2)
    dist = np.take_along_axis(dist, order, axis=-1)
    rho = np.take_along_axis(np.broadcast_to(rho, dist.shape[:-1] + (rho.shape[-1],)), order, -1)
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(dist > 0, 1.0 - rho / dist, 0.0)
    point = d * scale[..., None]  # the surface point, seen from the agent
    if frame_angle is not None:
        point = rotate(point, -frame_angle[..., None])
    gap = dist - rho - radii[:, None]
    out = np.concatenate([point, gap[..., None], np.ones_like(gap)[..., None]], axis=-1)
    return out.reshape(E, n, k * OBSTACLE_WIDTH)
