"""R-ORCA: ORCA's reciprocal half-planes with the R-SVO weights in place of its fixed one-half
split, as an active nominal controller for single integrators (``docs/liveness.md``).

ORCA (van den Berg et al., 2011) gives agent i, for each neighbour j within ``neighbor_dist``,
the smallest change ``u`` of the relative velocity that leaves the truncated velocity obstacle
(horizon ``tau``), and asks i to take half of it: the half-plane of velocities v with
``(v - (v_i + u / 2)) . n >= 0`` (``n`` the outward normal). Here agent i takes the share
``1 - omega_ij`` of ``u`` where it is avoidance (the relative velocity inside the obstacle) and
``omega_ij`` where it is slack (outside, ``u`` the room left to close), eq. ``rorca``: the egoist
(larger omega) does less of the avoidance and gets more of the slack, as the filter's rows give
it, and ``omega = 1/2`` is ORCA. Unlike a filter's rows these are *active*: an agent parked on
its goal whose velocity obstacle holds 0 must step aside, which is what makes crowds finish.
The velocity is the one closest to the preferred velocity within the half-planes and the speed
disk, by ORCA's own linear programs (``rsvo_env.qp.disk``); where they leave no room, the
velocity of the disk whose largest violation is least (ORCA's third). The R-CBF
filter on top keeps the guarantee whatever this controller proposes. Envs of at most
``sizes.ALL_PAIRS_MAX_AGENTS`` agents run ``rsvo_env.control.rorca.dense``'s stage (the
env's agents read in place, the weights from its matrix); larger ones this module's, over the
pairs of the grid search.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from rsvo_env.control.rorca import dense as rorca_dense
from rsvo_env.control.rorca import grid as rorca_grid

# ARRIVE, GOAL_REACH, HOLD_SECONDS and SIDESTEP are the rules' constants, read through this
# module
from rsvo_env.control.rorca.agent import (  # noqa: F401
    ARRIVE,
    GOAL_REACH,
    HOLD_SECONDS,
    SIDESTEP,
    blocked,
    cap_scale,
    cap_wanted,
    goal_gap,
    plane,
)
from rsvo_env.responsibility import pair_weights
from rsvo_env.responsibility.svo import Weighting, symmetric_envs
from rsvo_env.util import sizes

# ORCA's defaults: the 10 nearest neighbours within 5 pair distances (10 radii of the largest)
MAX_NEIGHBORS = 10
REACH_RADII = 10.0


@njit(cache=True)
def half_planes(x, v, radii, I, J, share, tau, dt, parked, seen):
    """Both directed half-planes of each pair (I, J): rows ``A . v <= b`` for agent I (first
    P) and agent J (last P), ``share`` (P, 2) each side's part of the avoidance (summing to 1;
    of the slack each side takes the other's share). An agent ``parked`` (M,) reads a neighbour
    en route at the velocity ``seen`` (M, 2) instead of its current one."""
    P = I.shape[0]
    A = np.empty((2 * P, 2))
    b = np.empty(2 * P)
    for p in range(P):
        for side in range(2):
            me, other = (I[p], J[p]) if side == 0 else (J[p], I[p])
            vo = seen[other] if parked[me] and not parked[other] else v[other]
            mine = (x[me, 0], x[me, 1], v[me, 0], v[me, 1])
            row = plane(
                mine,
                (x[other, 0], x[other, 1]),
                (vo[0], vo[1]),
                radii[me] + radii[other],
                share[p, side],
                share[p, 1 - side],
                1.0 / tau,
                dt,
            )
            k = p + side * P
            A[k, 0], A[k, 1], b[k] = row
    return A, b


def arrival_capped(
    preferred: NDArray,
    positions: NDArray,
    goals: NDArray,
    radii: NDArray,
    tau: float,
    I: NDArray[np.int64],
    J: NDArray[np.int64],
    held: NDArray[np.bool_] | None = None,
) -> NDArray[np.float64]:
    """``preferred`` (M, 2) scaled down to speed at most ``ARRIVE |goal - x| / tau`` where the
    look-ahead ``|preferred| tau`` passes the goal by more than the gap between the goal and a
    neighbour's body (pairs I, J; flat (M, 2) positions and goals, radii (M,)); with ``held``
    (M,), only there. The compiled stages cap as they scan; this form over a pair list is
    their reference (``tests/control/test_rorca.py``)."""
    M = len(positions)
    f = lambda a: np.ascontiguousarray(a, dtype=np.float64)  # noqa: E731
    hold = np.ones(M, dtype=np.bool_) if held is None else np.ascontiguousarray(held)
    out = np.empty((M, 2))
    _cap_pairs(
        f(positions),
        f(goals),
        f(preferred),
        f(radii),
        np.asarray(I, np.int64),
        np.asarray(J, np.int64),
        float(tau),
        hold,
        out,
    )
    return out


@njit(cache=True)
def _cap_pairs(x, g, pref, r, I, J, tau, held, out):
    """``arrival_capped``: each agent's gap (the least over its pairs, in any order), then
    its cap."""
    M = x.shape[0]
    gap = np.full(M, np.inf)
    for p in range(I.shape[0]):
        for me, other in ((I[p], J[p]), (J[p], I[p])):
            near = goal_gap((g[me, 0], g[me, 1]), (x[other, 0], x[other, 1]), r[me], r[other])
            gap[me] = min(gap[me], near)
    for a in range(M):
        pa = (pref[a, 0], pref[a, 1])
        wanted, speed, dist = cap_wanted(pa, (x[a, 0], x[a, 1]), (g[a, 0], g[a, 1]), held[a], tau)
        scale = cap_scale(wanted, speed, dist, tau, gap[a])
        out[a, 0], out[a, 1] = pa[0] * scale, pa[1] * scale


def goal_blocked(
    positions: NDArray,
    goals: NDArray,
    radii: NDArray,
    held: NDArray[np.bool_],
    reach: float = GOAL_REACH,
) -> NDArray[np.bool_]:
    """(...,) the agents ``held`` short of a goal within ``reach`` of their own radii
    (``radii``; at 3, a goal up to a body's width beyond the agent's own; at 0, none), which
    R-ORCA treats as parked. A neighbour's body may block such a goal, and an agent pressing
    for it pins that neighbour, which may be the very agent that must pass to free the goal
    (the crowd of 100 at its defaults, seed 3: an egoist 0.15 m short of its goal pinned an
    altruist between two parked agents for 20,000 steps). Parked, it yields, the neighbour
    passes, and it comes back (``docs/liveness.md``)."""
    shape = np.shape(positions)[:-1]
    rows = lambda a: np.ascontiguousarray(np.broadcast_to(a, shape + (2,)), np.float64)  # noqa: E731
    each = lambda a, t: np.ascontiguousarray(np.broadcast_to(a, shape), t).reshape(-1)  # noqa: E731
    out = np.empty(int(np.prod(shape)), np.bool_)
    _blocked_all(
        rows(positions).reshape(-1, 2),
        rows(goals).reshape(-1, 2),
        each(radii, np.float64),
        each(held, np.bool_),
        float(reach),
        out,
    )
    return out.reshape(shape)


@njit(cache=True)
def _blocked_all(x, g, r, held, reach, out):
    """``goal_blocked`` over flat rows, by the stages' own rule (``agent.blocked``)."""
    for a in range(x.shape[0]):
        out[a] = blocked((x[a, 0], x[a, 1]), (g[a, 0], g[a, 1]), r[a], held[a], reach)


class Rules(NamedTuple):
    """The state R-ORCA reads beyond the crowd's motion and scores: its rules' ``parked``
    (E, N) agents at their goals, ``goals`` (E, N, 2), ``held`` (E, N) agents held short of
    them; ``omega`` (E, N, N), the weight matrices of the scores where the caller keeps them
    (the simulation core does, ``State.omega``), read rather than computed again; and the goal
    rule's ``reach`` (``goal_blocked``) and ``goal_held`` (E, N), the agents held long
    enough for it (None: ``held``)."""

    parked: NDArray | None = None
    goals: NDArray | None = None
    held: NDArray | None = None
    omega: NDArray | None = None
    reach: float = GOAL_REACH
    goal_held: NDArray | None = None


def rorca_velocities(
    positions: NDArray,
    velocities: NDArray,
    preferred: NDArray,
    radii: NDArray,
    theta: NDArray,
    modes: list[Weighting],
    u_max: float,
    dt: float,
    tau: float = 2.0,
    neighbor_dist: float | None = None,
    max_neighbors: int | None = MAX_NEIGHBORS,
    rules: Rules | None = None,
) -> NDArray[np.float64]:
    """Eq. ``rorca``: each agent's velocity (E, N, 2) closest to ``preferred`` within its R-ORCA
    half-planes against the nearest ``max_neighbors`` (None: all) of the neighbours within
    ``neighbor_dist`` (default ``5 (r_i + r_j)`` of the largest pair), and the speed limit
    ``u_max`` (ORCA's defaults: 10 neighbours, 5 pair distances, horizon 2 s). ``radii``
    (E, N) or (N,); the weights come from the scores ``theta`` (E, N) and each env's weighting
    ``modes`` (``"symmetric"``: ORCA); ``parked`` (E, N): agents at their goals, which take all
    of the avoidance and none of the slack from agents en route, read at their preferred
    velocities, and so do the agents held short of goals within the goal rule's ``reach``
    (``goal_blocked``); ``goals`` (E, N, 2): near its goal, where its look-ahead reaches a
    neighbour, an agent's preferred speed is capped (``arrival_capped``), only the agents
    ``held`` (E, N) if given; these three, the ``reach`` and ``goal_held`` are ``rules``
    (``Rules``, None: none of them), and so are the weight matrices ``omega`` (E, N, N)
    of ``theta`` and ``modes`` where the caller keeps them (read, not computed again)."""
    parked, goals, held, omega, reach, goal_held = Rules() if rules is None else rules
    E, n = positions.shape[:2]
    M = E * n
    flat = lambda a: np.ascontiguousarray(a, dtype=np.float64).reshape(M, -1)  # noqa: E731
    x, v, pref0 = flat(positions), flat(velocities), flat(preferred)
    radii = np.asarray(radii, dtype=np.float64)
    # (N,) radii of one env are its flat ones: no broadcast (a call costs about 1 us)
    r = radii if radii.size == M else np.broadcast_to(radii, (E, n))
    r = np.ascontiguousarray(r).reshape(M)
    if neighbor_dist is None:
        neighbor_dist = REACH_RADII * float(r.max())
    # the arrival cap applies where goals are given (to the agents held, if given)
    g = x if goals is None else flat(goals)
    if goals is None:
        hold = np.zeros(M, np.bool_)
    else:
        hold = np.ones(M, np.bool_) if held is None else np.ascontiguousarray(held).reshape(M)
    K = -1 if max_neighbors is None else int(max_neighbors)
    motion, tied = (x, v, g, pref0, r), parked is not None
    settings = (K, float(u_max), float(tau), float(dt), float(neighbor_dist))
    flags = np.zeros(M, np.bool_) if parked is None else np.ascontiguousarray(parked, np.bool_)
    # the goal rule reads its own clock where given (and goals are), else the arrival cap's
    own = goal_held is not None and goals is not None
    goal_hold = np.ascontiguousarray(goal_held, np.bool_).reshape(M) if own else hold
    compiled = (flags.reshape(M), hold, tied, float(reach), goal_hold)
    if n > sizes.ALL_PAIRS_MAX_AGENTS:  # a grid scan for each agent's K nearest, ORCA's way
        if omega is None and any(callable(m) for m in modes):
            omega = pair_weights.weight_matrices(theta, modes)
        out = rorca_grid.stage(n, motion, theta, symmetric_envs(modes), omega, compiled, settings)
    else:  # every other agent of the env within neighbor_dist, its weights from the matrices
        W = pair_weights.weight_matrices(theta, modes) if omega is None else omega
        out = rorca_dense.stage(n, motion, W, compiled, settings)
    return out.reshape(E, n, 2)
