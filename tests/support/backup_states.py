"""States for the backup barrier's tests: its h over pairs and obstacles computed afresh from
the definition (not through the filter), safe crowds, and clusters built at h = 0."""

import numpy as np

from rsvo_env.dynamics import double_integrator_step
from rsvo_env.dynamics.barriers.stopping import stopping_reach
from rsvo_env.geometry.obstacles import nearest_points


def reach(v, a, dt):
    """Each agent's stopping reach (eq. ``reach``), box [-a, a]: L = s^2 / (2 a) + s dt / 2."""
    return stopping_reach(np.linalg.norm(v, axis=-1), a, dt)


def pair_h(p, v, radii, a, dt, I, J):
    """h_ij = |p_i - p_j| - r_i - r_j - L_i - L_j of the pairs (I, J), and the distance over
    r_i + r_j."""
    L = reach(v, a, dt)
    d = np.linalg.norm(p[I] - p[J], axis=-1)
    return d - radii[I] - radii[J] - L[I] - L[J], d / (radii[I] + radii[J])


def obstacle_h(p, v, radii, a, dt, capsules):
    """(N, O) h of every agent against every capsule, and each body's clearance over r_i."""
    L = reach(v, a, dt)
    near = nearest_points(p[None], capsules[None])[0]
    d = np.linalg.norm(p[:, None, :] - near, axis=-1) - capsules[None, :, 4]
    return d - radii[:, None] - L[:, None], d / radii[:, None]


def safe_crowd(rng, n, scale, speed, spacing=4.0):
    """n agents on a jittered grid (radii 0.2 - 1.2, limits 0.5 - 3, theta 0 - 10), random
    velocities of up to ``speed`` scaled down together until every pair has h >= 0, goals across
    the crowd. Units times ``scale``."""
    side = int(np.ceil(np.sqrt(n)))
    cells = np.stack(np.meshgrid(np.arange(side), np.arange(side)), -1).reshape(-1, 2)[:n]
    p = (cells + rng.uniform(-0.15, 0.15, (n, 2))) * spacing * scale
    radii = rng.uniform(0.2, 1.2, n) * scale
    a = rng.uniform(0.5, 3.0, n) * scale
    v = rng.normal(size=(n, 2)) * speed * scale / np.sqrt(2.0)
    goals = p[rng.permutation(n)] + rng.uniform(-1, 1, (n, 2)) * scale
    theta = rng.uniform(0, 10, n)
    return p, v, radii, a, goals, theta


def into_safe_set(p, v, radii, a, dt, I, J, capsules=None):
    """The velocities scaled down by one factor (halving) until every pair (and obstacle) has
    h >= 0."""
    for _ in range(60):
        ok = pair_h(p, v, radii, a, dt, I, J)[0].min(initial=np.inf) >= 0
        if capsules is not None and len(capsules):
            ok &= obstacle_h(p, v, radii, a, dt, capsules)[0].min() >= 0
        if ok:
            return v
        v = 0.5 * v
    raise AssertionError("the positions themselves are not safe")


def track(p, v, goals, a, v_max, k_v=2.0):
    """The nominal: a = k_v (v_des - v), v_des toward the goal at up to v_max, within each
    agent's box."""
    to_goal = goals - p
    d = np.linalg.norm(to_goal, axis=-1, keepdims=True)
    v_des = to_goal / np.maximum(d, 1e-300) * np.minimum(d, v_max)
    return np.clip(k_v * (v_des - v), -a[..., None], a[..., None])


def drive(flt, p, v, goals, radii, a, theta, dt, steps, v_max, I, J, capsules=None, hs=None):
    """Run the filtered crowd: the worst pair distance over r_i + r_j, the worst obstacle
    clearance over r_i, infeasible agent-steps while every h >= 0, and agent-steps in all.
    ``hs``: the barrier's (pair h, obstacle h) functions (default: the backup barrier's)."""
    pair_h, obstacle_h = hs or (globals()["pair_h"], globals()["obstacle_h"])
    worst, worst_o, infeasible = np.inf, np.inf, 0
    kw = {} if capsules is None else {"obstacles": capsules}
    for _ in range(steps):
        u = track(p, v, goals, a, v_max)
        res = flt.filter(p, u, theta, velocities=v, radii=radii, u_max=a, **kw)
        h, _ = pair_h(p, v, radii, a, dt, I, J)
        safe = h.min(initial=np.inf) >= 0
        if capsules is not None:
            safe &= obstacle_h(p, v, radii, a, dt, capsules.capsules)[0].min() >= 0
        infeasible += int(safe) * int((~res.feasible).sum())
        p, v = double_integrator_step(p, v, res.actions, dt)
        worst = min(worst, float(pair_h(p, v, radii, a, dt, I, J)[1].min(initial=np.inf)))
        if capsules is not None:
            worst_o = min(
                worst_o, float(obstacle_h(p, v, radii, a, dt, capsules.capsules)[1].min())
            )
    return worst, worst_o, infeasible, p, v


def cluster(rng, family, E, k, scale):
    """E clusters of k agents (E, k, 2): positions, velocities, radii, limits; ``family``:
    head-on, crossing, overtaking or converging (k agents from a circle toward its centre)."""
    radii = rng.uniform(0.2, 2.0, (E, k)) * scale
    a = rng.uniform(0.5, 3.0, (E, k)) * scale
    speed = rng.uniform(0.0, 8.0, (E, k)) * scale
    if family == "converging":
        ang = np.sort(rng.uniform(0, 2 * np.pi, (E, k)), axis=1)
        u = np.stack([np.cos(ang), np.sin(ang)], -1)
        p = u * 10.0 * scale
        heading = -u + rng.normal(0, 0.3, (E, k, 2))
    else:
        side = {
            "head-on": [[-1, 0], [1, 0]],
            "crossing": [[-1, 0], [0, -1]],
            "overtaking": [[-1, 0], [1, 0]],
        }[family]
        p = np.broadcast_to(np.array(side, float) * 10.0 * scale, (E, 2, 2)).copy()
        heading = -np.array(side, float) + rng.normal(0, 0.05, (E, 2, 2))
        if family == "overtaking":  # both move right, the one behind faster
            heading = np.broadcast_to([1.0, 0.0], (E, 2, 2)) + rng.normal(0, 0.05, (E, 2, 2))
            speed[:, 0] += speed[:, 1]
    heading /= np.linalg.norm(heading, axis=-1, keepdims=True)
    return p, heading * speed[..., None], radii, a
