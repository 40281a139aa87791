"""The unicycle (differential drive): axle position p, heading theta, inputs forward speed v in
[v_min, v_max] and turn rate w in [-w_max, w_max] (``docs/unicycle.md``).

The filter acts on the look-ahead point ``q = p + l e(theta)`` (the near-identity map of the
Robotarium): ``q' = R(theta) (v, l w)``, so in the agent's body frame the look-ahead point is a
single integrator with input ``c_b = (v, l w)``. Its rows are the single integrator's on q with
each body's radius enlarged by l (``|p_i - p_j| >= |q_i - q_j| - l_i - l_j``), rotated into the
agent's body frame, and its box keeps the inputs in their bounds for the whole step.
Over a step the look-ahead point's velocity ``c = R(theta_0) c_b`` is held (the near-identity
map run continuously): ``q+ = q + dt c`` exactly, and the heading relaxes toward c's direction
in closed form, ``tan(psi / 2)`` decaying as ``exp(-|c| t / l)`` (``psi = theta - angle(c)``).
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rsvo_env.dynamics.model import Dynamics
from rsvo_env.dynamics.single_integrator import SingleIntegrator
from rsvo_env.geometry.bodies import Bodies
from rsvo_env.util.planar import turn
from rsvo_env.util.validation import real_array, shown

if TYPE_CHECKING:
    from rsvo_env.util.settings import FilterSettings


def heading_vectors(headings: NDArray) -> NDArray[np.float64]:
    """(..., 2) the unit vectors ``(cos theta, sin theta)``."""
    return np.stack([np.cos(headings), np.sin(headings)], axis=-1)


def unicycle_step(
    positions: NDArray, headings: NDArray, u: NDArray, lookahead: float, dt: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The exact step of the look-ahead hold: ``u`` (..., 2) is (v, w) at the start of the
    step; the look-ahead point moves by ``dt R(theta) (v, l w)``, the heading relaxes toward
    that direction (module docstring). Returns axle positions and headings after ``dt``."""
    l = lookahead
    e = heading_vectors(headings)
    c = turn(np.stack([u[..., 0], l * u[..., 1]], -1), e[..., 0], e[..., 1])
    q = positions + l * e + dt * c
    speed = np.hypot(c[..., 0], c[..., 1])
    alpha = np.arctan2(c[..., 1], c[..., 0])
    psi = np.angle(np.exp(1j * (headings - alpha)))  # in (-pi, pi]
    # tan(psi / 2) decays as exp(-|c| t / l): psi keeps its sign and never crosses 0 or pi
    relaxed = alpha + 2.0 * np.arctan(np.tan(0.5 * psi) * np.exp(-speed * dt / l))
    new = np.where(speed > 0, relaxed, headings)
    new = np.where(np.abs(psi) == np.pi, headings, new)  # straight back: no turn
    return q - l * heading_vectors(new), new


class Unicycle(Dynamics):
    """Differential drive through its look-ahead point (``docs/unicycle.md``)."""

    name = "unicycle"
    limit_name = "u_max"
    state_fields = ("headings",)
    per_agent_bodies = True
    # its QP is the projection of (v, l w) onto a box that holds 0 and the turned rows
    nominal_disk = True
    # the look-ahead distance l and the turn-rate bound. l = 0.1 m: each body is enlarged by l
    # (R-ORCA's and the filter's), and a crowd of 100 at 0.2 took 1.54 times the single
    # integrator's makespan (1.72 at the defaults), at 0.1 1.33 (1.26); the sideways speed
    # l w_max = 0.3 m/s it leaves is enough (docs/unicycle.md, "The look-ahead distance")
    scenario_defaults = {"lookahead": 0.1, "w_max": 3.0}
    scenario_positive = ("lookahead", "w_max")

    def check_scenario(self, params, name):
        if params["lookahead"] * params["w_max"] >= params["u_max"]:
            raise ValueError(
                f"{name}: lookahead * w_max = {shown(params['lookahead'] * params['w_max'])} "
                f"must be "
                f"below u_max = {shown(params['u_max'])} (the forward speed limit)"
            )

    def body_margin(self, params):
        # the rows hold the look-ahead points r_i + r_j + 2 l apart; each is l from its axle
        return float(params["lookahead"])

    def start_bodies(self, starts, goals, radii, params):
        l = float(params["lookahead"])
        seg = goals - starts  # facing the goal, as the core starts it
        return starts + l * heading_vectors(np.arctan2(seg[..., 1], seg[..., 0])), radii + l

    def steered(self, state, params):
        """The look-ahead points, their velocities over the last step (the ``c`` each held),
        bodies enlarged by l."""
        l = float(params["lookahead"])
        q = state.positions + l * heading_vectors(state.headings)
        return q, state.steered_velocities, np.asarray(l)

    def track(self, state, velocity, params, limits):
        """The look-ahead velocity ``c`` as (v, w) (``toward``); where ``c`` points behind
        the robot, it turns in place toward it at ``|c| / l`` (at most ``w_max``): the inverse
        map would ask to reverse. ``v`` within [0, u_max], ``w`` within the turn-rate bound.

        The turn takes the shorter way, unless the agent has made no progress for a full turn's
        time ``2 pi / w_max`` (the state's ``no_progress`` clock) and faces more than 60 degrees
        off ``c``: then it turns left and right by turns, each a full turn at ``w_max``, since
        the shorter way can be the one a wall or a neighbour blocks (the look-ahead point
        swings toward it)."""
        l, w_max = float(params["lookahead"]), float(params["w_max"])
        v, w = np.moveaxis(self.toward(state.positions, state.headings, velocity, params), -1, 0)
        behind = v < 0.0
        speed = np.hypot(velocity[..., 0], velocity[..., 1])
        w = np.where(behind, np.where(w >= 0.0, 1.0, -1.0) * speed / l, w)
        if state.no_progress is not None:
            turns = np.floor(state.no_progress * params["dt"] * w_max / (2.0 * np.pi))
            # held, and more than 60 degrees off the wanted direction: it must turn
            swing = (turns >= 1.0) & (v < 0.5 * speed)
            w = np.where(swing, np.where(turns % 2.0 == 1.0, w_max, -w_max), w)
        v_max = params["u_max"] if limits is None else limits
        return np.stack([np.clip(v, 0.0, v_max), np.clip(w, -w_max, w_max)], -1)

    def check_box(self, cfg: FilterSettings, lo: NDArray, hi: NDArray) -> None:
        if cfg.lookahead is None or cfg.w_max is None:
            raise ValueError("FilterConfig: the unicycle needs lookahead (l > 0) and w_max")
        if not (lo[0] <= 0.0 <= hi[0]):
            raise ValueError(
                f"FilterConfig: the unicycle must be able to stop, v_min <= 0 <= v_max "
                f"(u_min <= 0 <= u_max), got v_min = {shown(lo[0])}, v_max = {shown(hi[0])}"
            )
        if cfg.lookahead * cfg.w_max >= hi[0]:
            raise ValueError(
                f"FilterConfig: lookahead * w_max = {shown(cfg.lookahead * cfg.w_max)} must be "
                f"below "
                f"v_max = {shown(hi[0])} (the look-ahead point's speed bounds the forward speed)"
            )

    def box(self, cfg: FilterSettings, lo: NDArray, hi: NDArray) -> tuple[NDArray, NDArray]:
        # c_b = (v, l w) with v >= 0: the heading turns toward c, so v(t) rises toward |c| and
        # |w(t)| only falls; |c_b| <= v_max and |l w| <= l w_max then keep every input in its
        # bounds for the whole step. Reversing (v < 0) could swing w past w_max on the way.
        assert cfg.lookahead is not None and cfg.w_max is not None  # the unicycle's config
        b = cfg.lookahead * cfg.w_max
        v_hi = float(np.sqrt(hi[0] ** 2 - b * b))
        return np.array([0.0, -b]), np.array([v_hi, b])

    def agent_boxes(self, cfg, u_max):
        """Each agent's body-frame box from its own forward-speed limit ``v_max,i``:
        ``0 <= v <= sqrt(v_max,i^2 - (l w_max)^2)``, ``|l w| <= l w_max`` (``box``)."""
        assert cfg.lookahead is not None and cfg.w_max is not None  # the unicycle's config
        b = cfg.lookahead * cfg.w_max
        slow = u_max <= b
        if slow.any():
            i = int(np.argmax(slow))
            raise ValueError(
                f"u_max[{i}] = {shown(float(u_max[i]))} must be above lookahead * w_max = "
                f"{shown(b)} "
                f"(agent {i}: the look-ahead point's speed bounds the forward speed)"
            )
        v_hi = np.sqrt(u_max * u_max - b * b)
        lo = np.stack([np.zeros_like(v_hi), np.full_like(v_hi, -b)], -1)
        return lo, np.stack([v_hi, np.full_like(v_hi, b)], -1)

    def filter_state(self, cfg, lead, n, single, bodies, state):
        hd = check_headings(state.get("headings"), (*lead, n), self.name)
        hd = hd[None] if single else hd
        if state.get("holonomic") is not None:
            mask = check_holonomic(state["holonomic"], (*lead, n)).reshape(-1)
            if bodies is None:
                bodies = Bodies.of(cfg, lead[0] if lead else 1, n)
            bodies = bodies.with_holonomic(mask, float(np.max(cfg.u_max)), cfg.lookahead)
        return bodies, {"headings": hd}

    def lift(self, cfg, positions, nominal, bodies, headings):
        M = len(bodies.radii)
        l = np.full(M, float(cfg.lookahead)) if bodies.lookahead is None else bodies.lookahead
        e = heading_vectors(headings).reshape(M, 2)
        # a holonomic agent (l = 0, a mixed crowd) is a single integrator in the world frame
        cos, sin = np.where(l > 0, e[:, 0], 1.0), np.where(l > 0, e[:, 1], 0.0)
        q = positions + (l[:, None] * e).reshape(positions.shape)
        nom = nominal.reshape(M, 2)
        nominal_b = np.stack([nom[:, 0], np.where(l > 0, l, 1.0) * nom[:, 1]], -1)
        # the world-frame box that holds each agent's rotated box: a valid (wider) box for
        # culling, since a row that cannot bind over it cannot bind over the rotated one
        mid, half = 0.5 * (bodies.lo + bodies.hi), 0.5 * (bodies.hi - bodies.lo)
        centre = turn(mid, cos, sin)
        ac, as_ = np.abs(cos), np.abs(sin)
        extent = np.stack(
            [ac * half[:, 0] + as_ * half[:, 1], as_ * half[:, 0] + ac * half[:, 1]], -1
        )
        radii = bodies.radii + l
        r_max = radii.reshape(len(bodies.r_max), -1).max(axis=1)
        row_bodies = Bodies.made(radii, centre - extent, centre + extent, r_max, False)
        # the rotated box's largest input is the body-frame box's (a turn keeps norms), not
        # the corner of the wider box that holds it: the culling radii take the smaller
        row_bodies = replace(row_bodies, speed=bodies.speed)
        return q, nominal_b.reshape(nominal.shape), row_bodies, np.stack([cos, sin], -1)

    def lower(self, cfg, actions, bodies):
        if bodies.lookahead is None:
            return np.stack([actions[..., 0], actions[..., 1] / cfg.lookahead], -1)
        l = bodies.lookahead.reshape(actions.shape[:-1])
        return np.stack([actions[..., 0], actions[..., 1] / np.where(l > 0, l, 1.0)], -1)

    def turn_rows(self, rows, rotation):
        return replace(rows, flat_A=rotate_rows(rows.flat_A, rows.owner, rotation))

    # the rows, radii and obstacle rows are the single integrator's on the look-ahead point
    rows = SingleIntegrator.rows
    culling_radii = SingleIntegrator.culling_radii
    obstacle_rows = SingleIntegrator.obstacle_rows
    barrier_over_all_pairs = SingleIntegrator.barrier_over_all_pairs

    def step(self, positions, velocities, u, dt):
        raise NotImplementedError(
            "the unicycle's state is (positions, headings): use rsvo_env.dynamics.unicycle_step"
        )

    def advance_state(self, state, u, dt, params):
        """The simulator's step: axle positions, headings, each axle's mean velocity over
        the step (what the observation reports) and each look-ahead point's (its ``c``)."""
        before, l = state.positions, float(params["lookahead"])
        q_before = before + l * heading_vectors(state.headings)
        state.positions, state.headings = unicycle_step(before, state.headings, u, l, dt)
        state.velocities = (state.positions - before) / dt
        state.steered_velocities = (
            state.positions + l * heading_vectors(state.headings) - q_before
        ) / dt

    def to_controls(self, actions, params, planar, limits):
        """Normalised actions in [-1, 1]^2 to (v, w): ``(a_0 v_max, a_1 w_max)``, each
        component clipped to [-1, 1] first (the action's own frame is the body's); ``v_max``
        each agent's own where ``limits`` (N,) are given."""
        a = np.clip(actions, -1.0, 1.0)
        return np.stack([a[..., 0] * _v_max(params, limits), a[..., 1] * params["w_max"]], -1)

    def to_actions(self, controls, params, planar, limits):
        """The inverse of ``to_controls`` (no clipping)."""
        return np.stack(
            [controls[..., 0] / _v_max(params, limits), controls[..., 1] / params["w_max"]], -1
        )

    def hold(self, controls, params, limits):
        """(v, w) held to ``|v| <= v_max`` (each agent's own) and ``|w| <= w_max``, the range of
        ``to_controls``."""
        v_max, w_max = _v_max(params, limits), params["w_max"]
        return np.stack(
            [np.clip(controls[..., 0], -v_max, v_max), np.clip(controls[..., 1], -w_max, w_max)], -1
        )

    def global_fields(self):
        return (("heading", -np.pi, np.pi),)

    def global_values(self, state, sel):
        h = state.headings[sel]
        return [np.arctan2(np.sin(h), np.cos(h))]

    def toward(self, positions, headings, velocity, params):
        """A world velocity ``c`` for the look-ahead point as (v, w): ``v = e . c``,
        ``w = e_perp . c / l`` (the near-identity map's inverse)."""
        e = heading_vectors(headings)
        along = (e * velocity).sum(-1)
        across = e[..., 0] * velocity[..., 1] - e[..., 1] * velocity[..., 0]
        return np.stack([along, across / params["lookahead"]], -1)

    def reach(self, params: dict[str, Any], limit: float, horizon: float) -> tuple[float, float]:
        # The look-ahead point moves at |c| <= hypot(v_max, l w_max); the heading turns at
        # most |c| / l, so the axle (l behind) moves at most 2 |c| a step on average, and stays
        # within l of the point: 2 |c| bounds each mean-velocity component.
        l = float(params["lookahead"])
        speed = float(np.hypot(limit, l * float(params["w_max"])))
        return speed * horizon + 2.0 * l, 2.0 * speed


def _v_max(params: dict[str, Any], limits: NDArray | None) -> float | NDArray:
    """The forward speed bound: the scenario's ``u_max``, or each agent's (N,)."""
    return params["u_max"] if limits is None else limits


def rotate_rows(A: NDArray, owner: NDArray, rotation: NDArray) -> NDArray[np.float64]:
    """Rows ``A . c <= b`` on world velocities as rows on body-frame inputs, ``c = R c_b``:
    ``A R(theta_owner)``; ``rotation`` (M, 2) each agent's (cos, sin)."""
    cos, sin = rotation[owner, 0], rotation[owner, 1]
    return np.stack([A[:, 0] * cos + A[:, 1] * sin, -A[:, 0] * sin + A[:, 1] * cos], -1)


__all__ = ["Bodies", "Unicycle", "heading_vectors", "rotate_rows", "unicycle_step"]


def check_headings(headings: ArrayLike | None, shape: tuple[int, ...], model: str) -> NDArray:
    """Finite headings (radians) of the given shape, required by ``model``."""
    if headings is None:
        raise ValueError(f"headings are required for the {model}")
    hd = real_array(headings, "headings")
    if hd.shape != shape:
        raise ValueError(f"headings has shape {hd.shape}, expected {shape}")
    if not np.isfinite(hd).all():
        idx = tuple(int(k) for k in np.argwhere(~np.isfinite(hd))[0])
        where = "".join(f"[{k}]" for k in idx)
        raise ValueError(
            f"headings{where} = {shown(float(hd[idx]))} is not finite (agent {idx[-1]})"
        )
    return hd


def check_holonomic(holonomic: ArrayLike, shape: tuple[int, ...]) -> NDArray[np.bool_]:
    """One bool per agent (True: a single integrator in a mixed crowd of unicycles)."""
    arr = np.asarray(holonomic)
    if arr.dtype != np.bool_:
        raise ValueError(f"holonomic must be bools (True: a single integrator), got {arr.dtype}")
    if arr.shape != shape:
        raise ValueError(f"holonomic has shape {arr.shape}, expected {shape}")
    return arr
