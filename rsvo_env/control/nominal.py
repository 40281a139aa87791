"""Scripted nominal controllers: move-to-goal, the right-hand rule, lane following.

The paper's nominal controller is ``u = -k (x - x_target)`` (Sec. V-A), scaled here to the speed
limit. The paper uses a "right hand heuristic rule" against deadlock without defining it; ours
rotates the nominal clockwise by a fixed angle while a neighbour is within a trigger distance
(`docs/scenarios.md`).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env.util.planar import as_rows, clip2, clip_norm, norm


@njit(cache=True)
def move_to_goal_into(x, g, k, limit, turn, c, s, out):
    """``move_to_goal`` on flat rows (M, 2) into ``out``: ``turn`` (M,) the rows the
    right-hand rule turns by the rotation ``c``, ``s`` (``clockwise``)."""
    for i in range(x.shape[0]):
        ux, uy = clip2(-k * (x[i, 0] - g[i, 0]), -k * (x[i, 1] - g[i, 1]), limit)
        if turn[i]:
            ux, uy = c * ux - s * uy, s * ux + c * uy
        out[i, 0], out[i, 1] = ux, uy


@functools.lru_cache(maxsize=32)
def clockwise(angle_deg: float) -> tuple[float, float]:
    """cos and sin of a clockwise turn by ``angle_deg``."""
    angle = -math.radians(angle_deg)
    return float(np.cos(angle)), float(np.sin(angle))


_NEVER = np.zeros(1, dtype=np.bool_)


def move_to_goal(
    positions: NDArray[np.float64],
    goals: NDArray[np.float64],
    k: float,
    u_max: float,
    turn: NDArray[np.bool_] | None = None,
    angle_deg: float = 0.0,
) -> NDArray[np.float64]:
    """``u = -k (x - goal)``, scaled to norm <= u_max (paper, Sec. V-A); with ``turn`` (...),
    the right-hand rule in the same pass: the rows where it is set turned clockwise by
    ``angle_deg``."""
    shape = positions.shape
    x, g = as_rows(positions, shape), as_rows(goals, shape)
    out = np.empty_like(x)
    if turn is None:
        active = np.broadcast_to(_NEVER, (x.shape[0],))
    else:
        active = np.ascontiguousarray(turn).reshape(-1)
    c, s = clockwise(float(angle_deg))
    move_to_goal_into(x, g, float(k), float(u_max), active, c, s, out)
    return out.reshape(shape)


@njit(cache=True)
def right_hand_active(
    nearest: NDArray[np.float64],
    at_goal: NDArray[np.bool_],
    trigger: float,
    stalled: NDArray[np.int64],
    dt: float,
    hold: float,
) -> NDArray[np.bool_]:
    """Agents for which the right-hand rule fires: the nearest neighbour closer than
    ``trigger``, the agent not at its goal, and no closer to it for ``hold`` seconds or more
    (``stalled`` steps of ``dt``: the stall clock, ``rsvo_env.control.stall.held``; a hold of 0
    every agent); arrays (..., N)."""
    return (nearest < trigger) & ~at_goal & (stalled * dt >= hold)


def lane_following(
    positions: NDArray[np.float64],
    velocities: NDArray[np.float64],
    lane_start: NDArray[np.float64],
    merge_point: NDArray[np.float64],
    v_des: float,
    k_v: float,
    k_lat: float,
    a_max: float,
) -> NDArray[np.float64]:
    """Acceleration that tracks ``v_des`` along each vehicle's lane, then up the main lane.

    Before the merge point (y below it) a vehicle follows the line from its lane start to the
    merge point; past it, the main lane x = merge_x heading +y. The command is a speed-tracking
    term along the lane plus a lateral spring-damper toward the lane line, scaled to
    norm <= a_max. Arrays are (..., N, 2); ``lane_start`` is (N, 2).
    """
    on_ramp = positions[..., 1] < merge_point[1]
    ramp_dir = merge_point - lane_start
    ramp_dir = ramp_dir / norm(ramp_dir)[..., None]
    main_dir = np.array([0.0, 1.0])
    direction = np.where(on_ramp[..., None], ramp_dir, main_dir)
    normal = np.stack([-direction[..., 1], direction[..., 0]], axis=-1)
    # both lane lines pass through the merge point
    lateral = np.einsum("...j,...j->...", positions - merge_point, normal)
    lateral_speed = np.einsum("...j,...j->...", velocities, normal)
    speed_along = np.einsum("...j,...j->...", velocities, direction)
    a = (k_v * (v_des - speed_along))[..., None] * direction - (
        k_lat * lateral + 2.0 * np.sqrt(k_lat) * lateral_speed
    )[..., None] * normal
    return clip_norm(a, a_max)
