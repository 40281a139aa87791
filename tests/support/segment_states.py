"""States for the stopping-segment barrier's tests: its h over pairs and obstacles computed afresh
from the definition (the exact distance of two segments, crossings included, not through the
filter's separating direction), and clusters built with their tightest h at 0."""

import numpy as np

from tests.support.backup_states import pair_h, reach


def point_segment(x, s0, s1):
    """Distance of points x to segments [s0, s1] (broadcast over leading axes)."""
    e = s1 - s0
    L2 = (e * e).sum(-1)
    t = np.clip(np.where(L2 > 0, ((x - s0) * e).sum(-1) / np.where(L2 > 0, L2, 1.0), 0.0), 0, 1)
    return np.linalg.norm(x - s0 - t[..., None] * e, axis=-1)


def _cross(o, a, b):
    return (a[..., 0] - o[..., 0]) * (b[..., 1] - o[..., 1]) - (a[..., 1] - o[..., 1]) * (
        b[..., 0] - o[..., 0]
    )


def segment_distance(a0, a1, b0, b1):
    """Exact distance of segments [a0, a1] and [b0, b1]: 0 where they cross, else the smallest
    endpoint-to-segment distance."""
    d = np.minimum.reduce(
        [
            point_segment(a0, b0, b1),
            point_segment(a1, b0, b1),
            point_segment(b0, a0, a1),
            point_segment(b1, a0, a1),
        ]
    )
    c1, c2 = _cross(a0, a1, b0), _cross(a0, a1, b1)
    c3, c4 = _cross(b0, b1, a0), _cross(b0, b1, a1)
    crossing = (c1 * c2 < 0) & (c3 * c4 < 0)
    return np.where(crossing, 0.0, d)


def ends(p, v, a, dt):
    """Each agent's stopping segment [p, p + v_hat L]."""
    L = reach(v, a, dt)
    s = np.linalg.norm(v, axis=-1, keepdims=True)
    unit = np.divide(v, s, out=np.zeros_like(v), where=s > 0)
    return p, p + unit * L[..., None]


def seg_pair_h(p, v, radii, a, dt, I, J):
    """(..., P) h_ij = dist(S_i, S_j) - r_i - r_j, and the bodies' distance over r_i + r_j."""
    p0, p1 = ends(p, v, a, dt)
    d = segment_distance(p0[..., I, :], p1[..., I, :], p0[..., J, :], p1[..., J, :])
    body = np.linalg.norm(p[..., I, :] - p[..., J, :], axis=-1)
    rr = radii[..., I] + radii[..., J]
    return d - rr, body / rr


def seg_obstacle_h(p, v, radii, a, dt, capsules):
    """(..., N, O) h_io = dist(S_i, segment_o) - r_i - rho_o, and each body's clearance over r_i."""
    p0, p1 = ends(p, v, a, dt)
    c0, c1 = capsules[:, 0:2], capsules[:, 2:4]
    d = segment_distance(p0[..., None, :], p1[..., None, :], c0, c1) - capsules[:, 4]
    body = point_segment(p[..., None, :], c0, c1) - capsules[:, 4]
    return d - radii[..., None], body / radii[..., None]


def tightest(p, v, radii, a, dt, capsules=None):
    """Each cluster's smallest h over its pairs and obstacles (E,)."""
    k = p.shape[-2]
    I, J = np.triu_indices(k, 1)
    h = seg_pair_h(p, v, radii, a, dt, I, J)[0].min(axis=-1, initial=np.inf)
    if capsules is not None:
        h = np.minimum(h, seg_obstacle_h(p, v, radii, a, dt, capsules)[0].min(axis=(-2, -1)))
    return h


def at_zero(p, v, radii, a, dt, centre, capsules=None):
    """The positions scaled about ``centre`` (E, 1, 2) by the smallest factor that keeps every h
    >= 0 (bisection to the last bit), so the tightest h is 0 to rounding."""
    lo = np.zeros(len(p))
    hi = np.ones(len(p))
    q = p - centre
    for _ in range(60):  # the factor at which the cluster is safe
        bad = tightest(centre + q * hi[:, None, None], v, radii, a, dt, capsules) < 0
        if not bad.any():
            break
        hi = np.where(bad, 2.0 * hi, hi)
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        ok = tightest(centre + q * mid[:, None, None], v, radii, a, dt, capsules) >= 0
        lo, hi = np.where(ok, lo, mid), np.where(ok, mid, hi)
    return centre + q * hi[:, None, None]


def obstacle_cluster(rng, family, E, k, scale):
    """E clusters of k agents heading into ``family``'s obstacles (one set for all): a long wall
    ("wall"), the corner of two walls ("corner") or a circle ("circle"). Returns positions,
    velocities, radii, limits, the obstacles' capsules (O, 5) and each cluster's centre of
    scaling (E, 1, 2), on the obstacle."""
    radii = rng.uniform(0.2, 2.0, (E, k)) * scale
    a = rng.uniform(0.5, 3.0, (E, k)) * scale
    speed = rng.uniform(0.0, 8.0, (E, k)) * scale
    if family == "wall":
        caps = np.array([[0.0, -1e3, 0.0, 1e3, 0.6]])
        p = np.stack([rng.uniform(-10, -2, (E, k)), rng.uniform(-5, 5, (E, k))], -1)
        heading = np.array([1.0, 0.0]) + rng.normal(0, 0.5, (E, k, 2))
        centre = np.stack([np.zeros(E), p[..., 1].mean(axis=1)], -1)[:, None]
    elif family == "corner":
        caps = np.array([[0.0, 0.0, 30.0, 0.0, 0.3], [0.0, 0.0, 0.0, 30.0, 0.3]])
        p = rng.uniform(2, 10, (E, k, 2))
        heading = np.array([-1.0, -1.0]) + rng.normal(0, 0.4, (E, k, 2))
        centre = np.zeros((E, 1, 2))
    else:
        caps = np.array([[0.0, 0.0, 0.0, 0.0, 1.5]])
        ang = rng.uniform(0, 2 * np.pi, (E, k))
        u = np.stack([np.cos(ang), np.sin(ang)], -1)
        p = u * 10.0
        heading = -u + rng.normal(0, 0.3, (E, k, 2))
        centre = np.zeros((E, 1, 2))
    heading /= np.linalg.norm(heading, axis=-1, keepdims=True)
    return p * scale, heading * speed[..., None], radii, a, caps * scale, centre * scale


def crowd_pair_h(p, v, radii, a, dt, I, J):
    """For the crowds' checks (is every h >= 0?): the stopping disk's h, a lower bound of the
    segment's, replaced by the segment's where it is below 0; the bodies' distance as is."""
    disk, body = pair_h(p, v, radii, a, dt, I, J)
    near = np.nonzero(disk < 0)[0]
    disk[near] = seg_pair_h(p, v, radii, a, dt, I[near], J[near])[0]
    return disk, body
