"""The observation of each agent, defined once: one table drives both its bounds and its values.

Agent i sees, relative to itself and float32: its own features, then the K nearest neighbours'
features, nearest first. ``frame="goal"`` rotates every vector into the agent's start-to-goal
frame (so rotated scenarios are the same task). With a stall clock (``rsvo_env.control.stall``), its
value follows the own features, before the neighbours'.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

FRAMES = ("world", "goal")
SQRT2 = float(np.sqrt(2.0))


@dataclass(frozen=True)
class Limits:
    """What bounds every observed value in an episode: positions within ``p`` of the origin,
    speeds within ``v`` per component, theta up to ``theta_max``, the safety radius ``R``, the
    stall clock up to ``stall``."""

    p: float
    v: float
    theta_max: float
    R: float
    stall: float = 0.0


def limits_for(scenario: Any) -> Limits:
    """Finite bounds on every position and velocity component a scenario's episode can reach:
    the arena (every start and goal) grown by what the speed or acceleration limit allows over
    ``max_steps``."""
    p = scenario.params
    lo, hi = scenario.arena()
    horizon = p["max_steps"] * p["dt"]
    extent = float(max(np.abs(lo).max(), np.abs(hi).max()))
    reach, vel = scenario.model.reach(p, scenario.u_max, horizon)
    # the largest pair distance: the neighbour gap's lower bound
    R = max(float(p["safety_radius"]), 2.0 * float(np.max(scenario.radii)))
    return Limits(extent + reach, vel, p["theta_max"], R)


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
# optional, after the own features: steps since the agent last came closer to its goal, scaled
STALL_FEATURE = Feature("stall", 1, lambda L: (0.0, L.stall))
NEIGHBOR_FEATURES = (
    Feature("rel_position", 2, lambda L: (-2 * L.p * SQRT2, 2 * L.p * SQRT2)),
    Feature("rel_velocity", 2, lambda L: (-2 * L.v * SQRT2, 2 * L.v * SQRT2)),
    # the neighbour's goal from the observer: where it is headed, and (equal to rel_position)
    # whether it is parked there
    Feature("rel_goal", 2, lambda L: (-2 * L.p * SQRT2, 2 * L.p * SQRT2)),
    Feature("omega", 1, lambda L: (0.0, 1.0)),
    Feature("theta", 1, lambda L: (0.0, L.theta_max)),
    Feature("gap", 1, lambda L: (-L.R, 2 * L.p * SQRT2)),
    Feature("present", 1, lambda L: (0.0, 1.0)),
)


OWN_WIDTH = sum(f.width for f in OWN_FEATURES)
NEIGHBOR_WIDTH = sum(f.width for f in NEIGHBOR_FEATURES)


def size(k: int, stall: bool = False) -> int:
    """Length D of one agent's observation with K neighbours (and the stall clock)."""
    return OWN_WIDTH + int(stall) + k * NEIGHBOR_WIDTH


def own_features(stall: bool) -> tuple[Feature, ...]:
    """The own features' table, with the stall clock last when it is observed."""
    return OWN_FEATURES + (STALL_FEATURE,) if stall else OWN_FEATURES


def bounds(
    limits: Limits, k: int, stall: bool = False
) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """(low, high) of one agent's observation, in the table's order."""

    def spread(table: tuple[Feature, ...]) -> tuple[list[float], list[float]]:
        lo, hi = [], []
        for f in table:
            a, b = f.bounds(limits)
            lo += [a] * f.width
            hi += [b] * f.width
        return lo, hi

    own_lo, own_hi = spread(own_features(stall))
    nb_lo, nb_hi = spread(NEIGHBOR_FEATURES)
    low = np.array(own_lo + nb_lo * k, dtype=np.float32)
    high = np.array(own_hi + nb_hi * k, dtype=np.float32)
    return low, high


# The layout the compiled kernel below writes; the tables above are checked against it on
# import, so they remain the one definition of order, widths and bounds.
_KERNEL_LAYOUT = (
    ("goal_offset", 2, "velocity", 2, "theta", 1),
    (
        "rel_position",
        2,
        "rel_velocity",
        2,
        "rel_goal",
        2,
        "omega",
        1,
        "theta",
        1,
        "gap",
        1,
        "present",
        1,
    ),
)
_TABLES = (OWN_FEATURES, NEIGHBOR_FEATURES)
if _KERNEL_LAYOUT != tuple(tuple(x for f in t for x in (f.name, f.width)) for t in _TABLES):
    # pragma: no cover - a table edited without its kernel
    raise ImportError("observation tables and the observation kernel disagree")


@njit(cache=True, inline="always")
def _fill(x, v, goals, theta, omega, by_index, nb, frame_angle, use_frame, radii, stall, own, out):
    # every value read into a local before the first write: the compiler cannot tell that
    # ``out`` shares no memory with the inputs, and would read them again after each write
    E, n, K = nb.shape
    for e in range(E):
        for i in range(n):
            c, s = 1.0, 0.0
            if use_frame:
                c, s = np.cos(-frame_angle[e, i]), np.sin(-frame_angle[e, i])
            xi, yi, ri = x[e, i, 0], x[e, i, 1], radii[i]
            gx, gy = goals[e, i, 0] - xi, goals[e, i, 1] - yi
            vx, vy = v[e, i, 0], v[e, i, 1]
            th, clock = theta[e, i], stall[e, i]
            o = out[e, i]
            o[0], o[1] = c * gx - s * gy, s * gx + c * gy
            o[2], o[3] = c * vx - s * vy, s * vx + c * vy
            o[4] = th
            if own > 5:
                o[5] = clock
            for k in range(K):
                j = nb[e, i, k]
                px, py = x[e, j, 0] - xi, x[e, j, 1] - yi
                qx, qy = v[e, j, 0] - vx, v[e, j, 1] - vy
                hx, hy = goals[e, j, 0] - xi, goals[e, j, 1] - yi
                w = omega[e, i, j] if by_index else omega[e, i, k]
                tj, R = theta[e, j], ri + radii[j]
                b = own + 10 * k
                rx, ry = c * px - s * py, s * px + c * py
                o[b], o[b + 1] = rx, ry
                o[b + 2], o[b + 3] = c * qx - s * qy, s * qx + c * qy
                o[b + 4], o[b + 5] = c * hx - s * hy, s * hx + c * hy
                o[b + 6] = w
                o[b + 7] = tj
                o[b + 8] = np.sqrt(rx * rx + ry * ry) - R
                o[b + 9] = 1.0


# One kernel per width of the own features, each inlining ``_fill`` with ``own`` a constant: the
# neighbours' blocks at fixed offsets compile to faster stores
@njit(cache=True)
def _observe(x, v, goals, theta, omega, by_index, nb, frame_angle, use_frame, radii, stall, out):
    _fill(
        x,
        v,
        goals,
        theta,
        omega,
        by_index,
        nb,
        frame_angle,
        use_frame,
        radii,
        stall,
        OWN_WIDTH,
        out,
    )


@njit(cache=True)
def _observe_clock(
    x, v, goals, theta, omega, by_index, nb, frame_angle, use_frame, radii, stall, out
):
    _fill(
        x,
        v,
        goals,
        theta,
        omega,
        by_index,
        nb,
        frame_angle,
        use_frame,
        radii,
        stall,
        OWN_WIDTH + 1,
        out,
    )


def observe(
    positions: NDArray[np.float64],
    velocities: NDArray[np.float64],
    goals: NDArray[np.float64],
    theta: NDArray[np.float64],
    neighbor_omega: NDArray[np.float64],
    neighbors: NDArray[np.int64],
    frame_angle: NDArray[np.float64] | None,
    radii: NDArray[np.float64],
    stall: NDArray[np.float64] | None = None,
    by_index: bool = False,
) -> NDArray[np.float32]:
    """Observations (E, N, D) float32 of E envs; ``neighbors`` (E, N, K) are local indices and
    ``neighbor_omega`` (E, N, K) each agent's weight against them, or with ``by_index`` the
    weight matrices (E, N, N), read at the neighbours' indices. ``frame_angle`` (E, N)
    rotates into each agent's goal frame (None: world frame); ``radii`` (N,) the body radii (a
    neighbour's ``gap`` is the centre distance less ``r_i + r_j``); ``stall`` (E, N): the stall
    clock, observed when given."""
    E, n, K = neighbors.shape
    out = np.empty((E, n, size(K, stall is not None)), dtype=np.float32)
    use_frame = frame_angle is not None
    angle = frame_angle if use_frame else np.zeros((E, n))
    clock = angle if stall is None else stall  # without a clock, an (E, N) array left unread
    # the kernel indexes any layout: no contiguous copies
    (_observe if stall is None else _observe_clock)(
        positions,
        velocities,
        goals,
        theta,
        neighbor_omega,
        by_index,
        neighbors,
        angle,
        use_frame,
        np.ascontiguousarray(radii, dtype=np.float64),
        clock,
        out,
    )
    return out
