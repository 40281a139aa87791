"""R-ORCA's solver (rsvo_env.qp.disk: ORCA's linear programs within the speed disk) against
clarabel's second-order cone programs, on random and adversarial families (nearly parallel rows,
rows tangent to the disk, duplicates, opposed pairs), from millimetres to kilometres: every
tolerance relative to the disk's radius."""

import clarabel
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import sparse

from rsvo_env.qp import disk

FAMILIES = ("random", "nearly_parallel", "tangent", "duplicates", "opposed")


def family(rng: np.random.Generator, kind: str, K: int, r: float, room: bool) -> np.ndarray:
    """Unit-normal rows (K, 3) ``a . v <= b`` about the disk of radius r: with ``room`` each
    keeps the centre (b >= 0), else most exclude it."""
    if K == 0:
        return np.zeros((0, 3))
    angles = rng.uniform(0, 2 * np.pi, K)
    b = r * rng.uniform(0.0, 1.2, K) if room else -r * rng.exponential(0.5, K)
    if kind == "nearly_parallel":
        angles = angles[0] + rng.normal(0, 1e-9, K) + np.pi * rng.integers(0, 2, K)
    elif kind == "tangent":  # lines that barely cut the disk (room) or leave only a sliver
        b = (1.0 if room else -1.0) * r * (1.0 - 10.0 ** -rng.uniform(0, 12, K))
    elif kind == "duplicates":
        angles[1::2], b[1::2] = angles[0::2][: K // 2], b[0::2][: K // 2]
    elif kind == "opposed":
        angles[1::2] = angles[0::2][: K // 2] + np.pi + rng.normal(0, 1e-6, K // 2)
    return np.ascontiguousarray(np.stack([np.cos(angles), np.sin(angles), b], axis=-1))


def cone_program(rows: np.ndarray, r: float, p: np.ndarray | None) -> np.ndarray:
    """clarabel, on the problem scaled to a unit disk: with ``p``, ``min |v - p|^2`` over the
    rows and the disk (returns v); without, ``min t`` s.t. ``a . v - b <= t`` in the disk
    (returns (v, t))."""
    K = len(rows)
    s = clarabel.DefaultSettings()
    s.verbose, s.tol_gap_abs, s.tol_gap_rel, s.tol_feas = False, 1e-12, 1e-12, 1e-12
    disk_rows = np.zeros((3, 3))
    disk_rows[1, 0], disk_rows[2, 1] = -1.0, -1.0  # s = (1, v): |v| <= 1
    cones = [clarabel.NonnegativeConeT(K), clarabel.SecondOrderConeT(3)]
    b = np.concatenate([rows[:, 2] / r, [1.0, 0.0, 0.0]])
    if p is not None:  # in v
        A = np.vstack([rows[:, :2], disk_rows[:, :2]])
        P, q = sparse.csc_matrix(np.eye(2)), -p / r
    else:  # in (v, t)
        A = np.vstack([np.hstack([rows[:, :2], -np.ones((K, 1))]), disk_rows])
        P, q = sparse.csc_matrix((3, 3)), np.array([0.0, 0.0, 1.0])
    sol = clarabel.DefaultSolver(P, q, sparse.csc_matrix(A), b, cones, s).solve()
    # at these tolerances clarabel at times stops at its reduced ones; anything else (a failure,
    # an iteration limit) and its point says nothing
    assert str(sol.status) in ("Solved", "AlmostSolved"), sol.status
    return np.array(sol.x) * r


def solved(rows, p, r):
    res = np.empty(2)
    room = disk.solve_disk(p[0], p[1], rows, len(rows), r, np.empty_like(rows), res)
    return room, res


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(FAMILIES), st.integers(0, 20),
       st.floats(-3.0, 3.0))  # fmt: skip
def test_with_room_the_velocity_is_the_cone_programs(seed, kind, K, log_scale):
    """Rows that keep the disk's centre: the velocity lies within every row and the disk to 1e-12
    of the radius and is no further from p than the cone program's (to 1e-10 r^2): as the
    distance squared is 2-strongly convex, within 1e-5 r of the projection. (Clarabel's own point
    can be 5e-5 r off along the disk's edge, where the distance is flat to first order.)"""
    rng = np.random.default_rng(seed)
    r = 10.0**log_scale
    rows = family(rng, kind, K, r, room=True)
    p = rng.uniform(-2 * r, 2 * r, 2)
    room, v = solved(rows, p, r)
    assert room
    assert np.hypot(*v) <= r * (1 + 1e-12)
    assert (rows[:, :2] @ v - rows[:, 2] <= 1e-12 * r).all()
    c = cone_program(rows, r, p)
    assert np.sum((v - p) ** 2) <= np.sum((c - p) ** 2) + 1e-10 * r**2, kind


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(FAMILIES), st.integers(1, 20),
       st.floats(-3.0, 3.0))  # fmt: skip
def test_without_room_the_largest_violation_is_least(seed, kind, K, log_scale):
    """Rows that mostly exclude the centre: where there is no room, the velocity lies in the
    disk and its largest violation is the cone program's least one (to 1e-7 of the radius); where
    there is, it meets every row as above."""
    rng = np.random.default_rng(seed)
    r = 10.0**log_scale
    rows = family(rng, kind, K, r, room=False)
    p = rng.uniform(-2 * r, 2 * r, 2)
    room, v = solved(rows, p, r)
    assert np.hypot(*v) <= r * (1 + 1e-12)
    worst = np.max(rows[:, :2] @ v - rows[:, 2])
    least = cone_program(rows, r, None)[2]
    if room:
        assert worst <= 1e-12 * r
    else:
        assert least > -1e-7 * r, (kind, least / r)
        assert abs(worst - least) <= 1e-7 * r, (kind, worst / r, least / r)


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(FAMILIES), st.integers(0, 12),
       st.booleans(), st.sampled_from([2.0**-30, 2.0**-10, 2.0**10, 2.0**30]))  # fmt: skip
def test_units_scale_the_velocity_exactly(seed, kind, K, room, scale):
    """The same crowd in other units: the velocity scales with it, bit for bit where the change
    of units is a power of two (exact in floating point), so no step of the solver compares a
    length with a constant of its own. (A factor of 1e-3 rounds the inputs, and a sliver of the
    disk amplifies that: the cone tests above cover 1e-3 to 1e3 to their tolerances.)"""
    rng = np.random.default_rng(seed)
    rows = family(rng, kind, K, 1.0, room=room)
    p = rng.uniform(-2, 2, 2)
    big = rows.copy()
    big[:, 2] *= scale
    one, v = solved(rows, p, 1.0)
    other, w = solved(big, p * scale, scale)
    assert one == other
    assert (w / scale == v).all(), w / scale - v


def test_an_empty_row_set_clips_to_the_disk():
    rows = np.zeros((0, 3))
    assert solved(rows, np.array([3.0, 4.0]), 2.0)[1].tolist() == [1.2, 1.6]
    assert solved(rows, np.array([0.3, -0.4]), 2.0)[1].tolist() == [0.3, -0.4]


def test_two_opposed_rows_meet_halfway():
    """v_x <= -1 and v_x >= 1 in the disk of radius 5: both violated by 1 at v_x = 0."""
    rows = np.array([[1.0, 0.0, -1.0], [-1.0, 0.0, -1.0]])
    room, v = solved(rows, np.array([3.0, 2.0]), 5.0)
    assert not room and v[0] == 0.0 and abs(v[1]) <= 5.0


def test_a_row_past_the_disk_leaves_its_nearest_point():
    """v_x <= -7 with the disk of radius 5: the least violation is at (-5, 0)."""
    room, v = solved(np.array([[1.0, 0.0, -7.0]]), np.array([1.0, 1.0]), 5.0)
    assert not room and v.tolist() == [-5.0, 0.0]


def concurrent(rng: np.random.Generator, K: int, r: float, q: np.ndarray, spread: float):
    """K unit-normal rows whose lines all pass through q (``a . v <= a . q``): their only common
    point may be q itself, a chord that rounds to a point. ``spread`` 0: directions anywhere;
    else within ``spread`` radians of one (nearly parallel lines) or of its opposite."""
    angles = rng.uniform(0, 2 * np.pi, K)
    if spread:
        angles = angles[0] + rng.uniform(-spread, spread, K) + np.pi * rng.integers(0, 2, K)
    a = np.stack([np.cos(angles), np.sin(angles)], axis=-1)
    return np.ascontiguousarray(np.concatenate([a, (a @ q)[:, None]], axis=-1))


def test_lines_through_one_feasible_point_keep_it():
    """Five rows whose lines pass through q = (-0.375, 0.125) in the unit disk, preferred
    (-1.25, 0.75): in 2,500 draws of their directions there is room, and the velocity is never
    further from p than q (the solver once read the chord that rounds to q as empty and
    returned the least-violating velocity, up to 1.46 r too far)."""
    q, p = np.array([-0.375, 0.125]), np.array([-1.25, 0.75])
    rng = np.random.default_rng(0)
    for _ in range(2500):
        rows = concurrent(rng, 5, 1.0, q, 0.0)
        room, v = solved(rows, p, 1.0)
        assert room
        assert np.hypot(*(v - p)) <= np.hypot(*(q - p)) + 1e-12
        assert (rows[:, :2] @ v - rows[:, 2] <= 1e-12).all()


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(2, 12), st.floats(-3.0, 3.0),
       st.sampled_from([0.0, 1e-3, 1e-9]), st.floats(0.0, 1.0), st.booleans())  # fmt: skip
def test_concurrent_and_tangent_lines_are_the_cone_programs(
    seed, K, log_scale, spread, depth, tangent
):
    """Lines through one point q (anywhere in the disk, on its edge with ``depth`` 1), the
    directions anywhere or nearly parallel; with ``tangent`` one more row ``a . v <= -r``
    leaves the disk's one point -r a and the lines pass through it. Millimetres to kilometres:
    room, every row met to 1e-12 r, and no further from p than clarabel's projection."""
    rng = np.random.default_rng(seed)
    r = 10.0**log_scale
    angle = rng.uniform(0, 2 * np.pi)
    edge = np.array([np.cos(angle), np.sin(angle)])
    q = -r * edge if tangent else r * depth * edge
    rows = concurrent(rng, K, r, q, spread)
    if tangent:
        rows = np.ascontiguousarray(np.vstack([[*edge, -r], rows])[rng.permutation(K + 1)])
    p = rng.uniform(-2 * r, 2 * r, 2)
    room, v = solved(rows, p, r)
    assert room
    assert np.hypot(*v) <= r * (1 + 1e-12)
    assert (rows[:, :2] @ v - rows[:, 2] <= 1e-12 * r).all()
    # q meets every row; the crossing of two lines at an angle of sine s is known to about
    # 1e-16 / s of r, and lines within the solver's PARALLEL are one line to it
    ax, ay = rows[:, 0], rows[:, 1]
    sines = np.abs(ax[:, None] * ay[None, :] - ay[:, None] * ax[None, :])
    least = sines[~np.eye(len(rows), dtype=bool)].min()
    if least > 1e-12:
        assert np.hypot(*(v - p)) <= np.hypot(*(q - p)) + (1e-12 + 1e-15 / least) * r
    if tangent:  # the disk's one point within the tangent row (a sliver of width 1e-13 r)
        assert np.hypot(*(v - q)) <= 1e-6 * r
        return
    if spread == 1e-9:
        # lines 1e-9 apart: a point 1e-9 r off every row can be r from the feasible set, and
        # clarabel's tolerance admits such points; q is the bound above
        return
    # clarabel's point can violate the rows of these degenerate programs by 2e-8 r, which buys
    # it up to about 1e-7 r^2 of distance
    c = cone_program(rows, r, p)
    assert np.sum((v - p) ** 2) <= np.sum((c - p) ** 2) + 1e-7 * r**2
