"""The least largest violation (rsvo_env.qp.least_violation) against an LP solved by HiGHS, on
random and adversarial families (nearly parallel rows, rows through box corners, duplicates,
opposed pairs), from millimetres to kilometres: every tolerance relative to the box."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rsvo_env.qp import least_violation, reference

FAMILIES = ("random", "nearly_parallel", "corners", "duplicates", "opposed")


def family(rng: np.random.Generator, kind: str, K: int, s: float) -> tuple[np.ndarray, ...]:
    """Unit-normal rows (K, 3) ``a . u <= b`` over the box [-s, s]^2 that mostly conflict."""
    angles = rng.uniform(0, 2 * np.pi, K)
    b = -s * rng.exponential(0.5, K)  # each row excludes the box's centre
    if kind == "nearly_parallel":
        angles = angles[0] + rng.normal(0, 1e-9, K) + np.pi * rng.integers(0, 2, K)
    elif kind == "corners":
        corners = s * rng.choice([-1.0, 1.0], (K, 2))
        b = np.einsum("kd,kd->k", np.stack([np.cos(angles), np.sin(angles)], -1), corners)
    elif kind == "duplicates":
        angles[1::2], b[1::2] = angles[0::2][: K // 2], b[0::2][: K // 2]
    elif kind == "opposed":
        angles[1::2] = angles[0::2][: K // 2] + np.pi + rng.normal(0, 1e-6, K // 2)
    rows = np.stack([np.cos(angles), np.sin(angles), b], axis=-1)
    return np.ascontiguousarray(rows), np.full(2, -s), np.full(2, s)


def check(seed: int, kind: str, K: int, log_scale: float) -> None:
    rng = np.random.default_rng(seed)
    s = 10.0**log_scale
    rows, lo, hi = family(rng, kind, K, s)
    start = rng.uniform(lo, hi)
    t, x, y = least_violation.min_max(rows, K, lo[0], lo[1], hi[0], hi[1], s, *start)
    # the point is in the box and attains t
    assert lo[0] <= x <= hi[0] and lo[1] <= y <= hi[1]
    assert abs(t - np.max(rows[:, :2] @ [x, y] - rows[:, 2])) <= 1e-12 * s
    # the LP's optimum, on the problem scaled to a unit box (HiGHS's tolerances are absolute)
    _, t_star = reference.least_violation(rows[:, :2], rows[:, 2] / s, lo / s, hi / s)
    assert abs(t / s - t_star) <= 1e-9, (kind, t / s, t_star)


@settings(max_examples=300, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.sampled_from(FAMILIES),
    st.integers(1, 30),
    st.floats(-3.0, 3.0),
)
def test_the_least_violation_is_the_lps(seed, kind, K, log_scale):
    check(seed, kind, K, log_scale)


def test_two_opposed_rows_meet_halfway():
    """u_x <= -1 and -u_x <= -1 (u_x >= 1) over [-5, 5]^2: both violated by 1 at u_x = 0."""
    rows = np.array([[1.0, 0.0, -1.0], [-1.0, 0.0, -1.0]])
    t, x, _ = least_violation.min_max(rows, 2, -5.0, -5.0, 5.0, 5.0, 5.0, 3.0, 2.0)
    assert t == 1.0 and x == 0.0


def test_a_row_beyond_the_box_is_least_violated_at_the_nearest_edge():
    """u_x + u_y <= -30 over [-10, 10]^2: least violated at the corner (-10, -10), by 20/sqrt 2
    once normalised."""
    a = np.array([1.0, 1.0]) / np.sqrt(2.0)
    rows = np.array([[a[0], a[1], -30.0 / np.sqrt(2.0)]])
    t, x, y = least_violation.min_max(rows, 1, -10.0, -10.0, 10.0, 10.0, 10.0, 0.0, 0.0)
    assert (x, y) == (-10.0, -10.0)
    assert abs(t - 10.0 / np.sqrt(2.0)) <= 1e-12 * 10.0
