"""The observation of each agent, defined once: one table drives both its bounds and its values.

Agent i sees, relative to itself and float32: its own features, then the K nearest neighbours'
features, nearest first. ``frame="goal"`` rotates every vector into the agent's start-to-goal
frame (so rotated scenarios are the same task).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from rsvo_env.nominal import rotate

FRAMES = ("world", "goal")
SQRT2 = float(np.sqrt(2.0))


@dataclass(frozen=True)
class Limits:
    """What bounds every observed value in an episode: positions within ``p`` of the origin,
    speeds within ``v`` per component, theta up to ``theta_max``, the safety radius ``R``."""

    p: float
    v: float
    theta_max: float
    R: float


@dataclass(frozen=True)
class Feature:
    name: str
    width: int
    # (lo, hi) of each component; a rotated vector component can grow by sqrt(2)
    bounds: Callable[[Limits], tuple[float, float]]


OWN_FEATURES = (
    Feature("goal_offset", 2, lambda L: (-2 * L.p * SQRT2, 2 * L.p * SQRT2)),
    Feature("velocity", 2, lambda L: (-L.v * SQRT2, L.v * SQRT2)),
    Feature("theta", 1, lambda L: (0.0, L.theta_max)),
)
NEIGHBOR_FEATURES = (
    Feature("rel_position", 2, lambda L: (-2 * L.p * SQRT2, 2 * L.p * SQRT2)),
    Feature("rel_velocity", 2, lambda L: (-2 * L.v * SQRT2, 2 * L.v * SQRT2)),
    Feature("omega", 1, lambda L: (0.0, 1.0)),
    Feature("theta", 1, lambda L: (0.0, L.theta_max)),
    Feature("gap", 1, lambda L: (-L.R, 2 * L.p * SQRT2)),
    Feature("present", 1, lambda L: (0.0, 1.0)),
)


def size(k: int) -> int:
    """Length D of one agent's observation with K neighbours."""
    return sum(f.width for f in OWN_FEATURES) + k * sum(f.width for f in NEIGHBOR_FEATURES)


def bounds(limits: Limits, k: int) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """(low, high) of one agent's observation, in the table's order."""

    def spread(table: tuple[Feature, ...]) -> tuple[list[float], list[float]]:
        lo, hi = [], []
        for f in table:
            a, b = f.bounds(limits)
            lo += [a] * f.width
            hi += [b] * f.width
        return lo, hi

    own_lo, own_hi = spread(OWN_FEATURES)
    nb_lo, nb_hi = spread(NEIGHBOR_FEATURES)
    low = np.array(own_lo + nb_lo * k, dtype=np.float32)
    high = np.array(own_hi + nb_hi * k, dtype=np.float32)
    return low, high


def observe(
    positions: NDArray[np.float64],
    velocities: NDArray[np.float64],
    goals: NDArray[np.float64],
    theta: NDArray[np.float64],
    omega: NDArray[np.float64],
    neighbors: NDArray[np.int64],
    frame_angle: NDArray[np.float64] | None,
    safety_radius: float,
) -> NDArray[np.float32]:
    """Observations (E, N, D) float32 of E envs; ``neighbors`` (E, N, K) are local indices.
    ``frame_angle`` (E, N) rotates into each agent's goal frame (None: world frame)."""
    E, n, K = neighbors.shape
    flat = neighbors + (n * np.arange(E))[:, None, None]
    x, v = positions, velocities
    rel_p = x.reshape(-1, 2)[flat] - x[:, :, None, :]
    rel_v = v.reshape(-1, 2)[flat] - v[:, :, None, :]
    goal, vel = goals - x, v
    if frame_angle is not None:
        ang = -frame_angle
        goal, vel = rotate(goal, ang), rotate(vel, ang)
        rel_p = rotate(rel_p, ang[..., None])
        rel_v = rotate(rel_v, ang[..., None])
    own = {"goal_offset": goal, "velocity": vel, "theta": theta[..., None]}
    near = {
        "rel_position": rel_p,
        "rel_velocity": rel_v,
        "omega": np.take_along_axis(omega, neighbors, axis=-1)[..., None],
        "theta": theta.reshape(-1)[flat][..., None],
        "gap": (np.linalg.norm(rel_p, axis=-1) - safety_radius)[..., None],
        "present": np.ones((E, n, K, 1)),
    }
    parts = [own[f.name] for f in OWN_FEATURES]
    parts.append(
        np.concatenate([near[f.name] for f in NEIGHBOR_FEATURES], axis=-1).reshape(E, n, -1)
    )
    return np.concatenate(parts, axis=-1).astype(np.float32)
