"""The scenarios' scripted R-ORCA in one compiled call, for envs of more than
``sizes.ALL_PAIRS_MAX_AGENTS`` agents on one thread: the move-to-goal velocities
(``control.nominal``), the routing around knots (``route``), the rules' clocks (``stall.held``)
and the grid stage (``grid``): the same functions, and so the same velocities bit for bit, as
``Controller.nominal`` and ``scripted.steer`` call one by one, without the array conversions
and dispatches between them (what a user's ``nominal_actions()`` costs:
``benchmarks/results/rorca_speed.md``)."""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env.control.nominal import clockwise, move_to_goal_into
from rsvo_env.control.rorca import grid, route
from rsvo_env.control.rorca.agent import HOLD_SECONDS
from rsvo_env.control.rorca.velocities import MAX_NEIGHBORS, REACH_RADII
from rsvo_env.responsibility.svo import symmetric_envs
from rsvo_env.util import sizes, threads


@njit(cache=True)
def _clocks(no_progress, reached, rules, held, goal_held):
    """The rules' clocks (``stall.held``): ``held`` the agents stalled ``HOLD_SECONDS`` or more,
    ``goal_held`` those stalled the goal rule's hold or more (or that have reached their goals,
    where the rule says so); ``rules`` (dt, hold, goal_hold, goal_reached)."""
    dt, hold, goal_hold, goal_reached = rules
    for a in range(held.shape[0]):
        t = no_progress[a] * dt
        held[a] = t >= hold
        goal_held[a] = t >= goal_hold or (goal_reached and reached[a])


# the headings routing tries, compiled in as constants
_COS, _SIN, _DEGREES = route.HEADINGS


@functools.lru_cache(maxsize=64)
def _symmetric(modes: tuple) -> NDArray[np.bool_]:
    """``symmetric_envs`` of the envs' weightings, kept: they change only with a new mode."""
    out = symmetric_envs(modes)
    out.flags.writeable = False
    return out


@njit(cache=True)
def _steer(motion, radii, flags, rules, routing, weights, settings):
    """``scripted.steer`` in one call: ``motion`` (points, their velocities, goals, preferred
    velocities, each (E, N, 2)), ``radii`` (N,) or (E, N) before the pad, ``flags`` (at goal,
    reached, stall steps, each (E, N)), ``rules`` (dt, hold, goal_hold, goal_reached, reach,
    pad), ``routing`` (on, the safety radius, the stuck speed), ``weights`` (theta (E, N), the
    weight matrices (E, N, N) or (0, 0, 0), the symmetric envs (E,)), ``settings`` (K, u_max,
    tau, dt). Returns the velocities (E, N, 2)."""
    points, velocities, goals, preferred = motion
    E, n = points.shape[0], points.shape[1]
    M = E * n
    x, v = points.reshape(M, 2), velocities.reshape(M, 2)
    g = goals.reshape(M, 2)
    at_goal, reached, no_progress = flags[0].reshape(M), flags[1].reshape(M), flags[2].reshape(M)
    pad = rules[5]
    r = np.empty(M)
    flat_radii = radii.reshape(-1)
    for a in range(M):
        r[a] = pad * flat_radii[a % flat_radii.shape[0]]
    wanted = preferred.reshape(M, 2).copy()
    if routing[0]:
        route.route_envs(points, velocities, goals, flags[0], routing[1], routing[2], _COS, _SIN,
                         _DEGREES, wanted.reshape(E, n, 2))  # fmt: skip
    held = np.empty(M, np.bool_)
    goal_held = np.empty(M, np.bool_)
    _clocks(no_progress, reached, rules[:4], held, goal_held)
    theta, omega, symmetric = weights
    W = omega.reshape(-1, n) if omega.shape[0] > 0 else np.zeros((0, n))
    cut = REACH_RADII * r.max()
    out = np.empty((M, 2))
    grid.stage_serial(n, (x, v, g, wanted, r), theta.reshape(M), (at_goal, held, True, rules[4],
                      goal_held), W, symmetric, (settings[0], settings[1], settings[2],
                      settings[3], cut), out)  # fmt: skip
    return out.reshape(E, n, 2)


@njit(cache=True)
def _nominal(move, motion, radii, flags, rules, routing, weights, settings):
    """``_steer`` of the move-to-goal velocities (``control.nominal.move_to_goal``):
    ``move`` (positions (E, N, 2), gain k, speed, whether the right-hand rule turns, the agents
    it turns (E, N), its rotation's cosine and sine); ``motion`` (points, their velocities,
    goals)."""
    positions, k, speed, turning, active, c, s = move
    E, n = positions.shape[0], positions.shape[1]
    M = E * n
    turn = active.reshape(M) if turning else np.zeros(M, np.bool_)
    preferred = np.empty((M, 2))
    move_to_goal_into(positions.reshape(M, 2), motion[2].reshape(M, 2), k, speed, turn, c, s,
                      preferred)  # fmt: skip
    return _steer((motion[0], motion[1], motion[2], preferred.reshape(E, n, 2)), radii, flags,
                  rules, routing, weights, settings)  # fmt: skip


def _contiguous(a: NDArray, dtype: type) -> NDArray:
    return a if a.flags.c_contiguous and a.dtype == dtype else np.ascontiguousarray(a, dtype)


def nominal(
    state: Any,
    move: tuple,
    points: NDArray,
    point_velocities: NDArray,
    radii: NDArray,
    settings: Any,
    safety_radius: float,
    dt: float,
    speed: float,
) -> NDArray | None:
    """``scripted.steer``'s velocities (E, N, 2) from the move-to-goal ones in one compiled call,
    or None where that call does not serve: envs of at most ``sizes.ALL_PAIRS_MAX_AGENTS``
    agents (the dense stage), a parallel launch, a state without the stall clock, a callable
    weighting whose matrices the state does not keep. ``move``: (positions (E, N, 2), gain k,
    the agents the right-hand rule turns (E, N) or None, its angle in degrees); the rest as
    ``scripted.steer``'s."""
    E, n = points.shape[:2]
    omega, modes = state.omega, state.weighting
    if (
        n <= sizes.ALL_PAIRS_MAX_AGENTS
        or threads.parallel(E * n)
        or state.no_progress is None
        or (omega is None and any(callable(m) for m in modes))
    ):
        return None
    positions, k, turn, angle = move
    s, f = settings, np.float64
    c, sin = clockwise(float(angle))
    active = _NEVER if turn is None else _contiguous(turn, np.bool_)
    motion = (_contiguous(points, f), _contiguous(point_velocities, f), _contiguous(state.goals, f))
    flags = (_contiguous(state.at_goal, np.bool_), _contiguous(state.reached, np.bool_),
             _contiguous(state.no_progress, np.int64))  # fmt: skip
    rules = (float(dt), HOLD_SECONDS, float(s.rorca_goal_hold), bool(s.rorca_goal_reached),
             float(s.rorca_goal_reach), float(s.rorca_pad))  # fmt: skip
    routing = (bool(s.rorca_route), float(safety_radius), route.SLOW * float(speed))
    W = _NO_MATRICES if omega is None else _contiguous(omega, f)
    weights = (_contiguous(state.theta, f), W, _symmetric(tuple(modes)))
    move_args = (_contiguous(positions, f), float(k), float(speed), turn is not None, active, c,
                 sin)  # fmt: skip
    return _nominal(move_args, motion, _contiguous(radii, f), flags, rules, routing, weights,
                    (MAX_NEIGHBORS, float(speed), float(s.rorca_tau), float(dt)))  # fmt: skip


_NO_MATRICES = np.zeros((0, 0, 0))
_NEVER = np.zeros((1, 1), dtype=np.bool_)
