"""Random and degenerate 2-D QP instances shared by the solver tests and the benchmark."""

from __future__ import annotations

import numpy as np

KINDS = ("random", "parallel", "on_boundary", "duplicate", "corner", "infeasible")


def make_instance(rng: np.random.Generator, K: int, kind: str) -> dict:
    """One QP ``min |u - nominal|^2`` s.t. ``lo <= u <= hi``, ``A u <= b`` of the given kind.

    Feasible kinds build every row around a point ``u0`` inside the box, so feasibility is known
    by construction; ``infeasible`` adds a row that excludes the whole box by a clear margin.
    """
    u_max = rng.uniform(0.5, 4.0)
    lo, hi = np.full(2, -u_max), np.full(2, u_max)
    nominal = rng.uniform(-2.0 * u_max, 2.0 * u_max, 2)
    u0 = rng.uniform(lo, hi)
    normals = rng.normal(size=(K, 2)) * rng.uniform(0.1, 10.0, (K, 1))
    b = normals @ u0 + rng.exponential(u_max, K) * np.linalg.norm(normals, axis=1)
    if kind == "parallel" and K >= 2:
        normals[1::2] = normals[0] * rng.uniform(0.2, 5.0, (len(normals[1::2]), 1))
        b[1::2] = normals[1::2] @ u0 + rng.uniform(0.0, 1.0, len(normals[1::2]))
    elif kind == "on_boundary":
        # the nominal sits exactly on row 0's line, inside the box, and row 0 still contains u0
        c = rng.uniform(0.9 * lo, 0.9 * hi)
        if normals[0] @ (c - u0) < 0:
            normals[0] = -normals[0]
        b[0] = normals[0] @ c
        nominal = c
    elif kind == "duplicate" and K >= 2:
        normals[1] = normals[0]
        b[1] = b[0]
        b[0] = normals[0] @ u0  # and make it bind at u0
        b[1] = b[0]
    elif kind == "corner":
        corner = np.array([lo[0], lo[1]])
        normals[0] = np.array([1.0, 1.0]) * rng.uniform(0.5, 3.0)
        b[0] = normals[0] @ corner
        # every other row must contain the corner, or the instance is infeasible
        b[1:] = normals[1:] @ corner + rng.exponential(1.0, K - 1)
    elif kind == "infeasible":
        a = rng.normal(size=2)
        a /= np.linalg.norm(a)
        support_min = np.minimum(a * lo, a * hi).sum()
        normals[0] = a * rng.uniform(0.5, 5.0)
        b[0] = (support_min - rng.uniform(0.05, 2.0)) * np.linalg.norm(normals[0]) / 1.0
    return {
        "nominal": nominal,
        "A": normals,
        "b": b,
        "lo": lo,
        "hi": hi,
        "feasible": kind != "infeasible",
    }


def make_batch(rng: np.random.Generator, count: int, K: int, kinds=KINDS) -> list[dict]:
    return [make_instance(rng, K, kinds[i % len(kinds)]) for i in range(count)]


def stack(instances: list[dict]) -> tuple[np.ndarray, ...]:
    nominal = np.stack([p["nominal"] for p in instances])
    A = np.stack([p["A"] for p in instances])
    b = np.stack([p["b"] for p in instances])
    lo = np.stack([p["lo"] for p in instances])
    hi = np.stack([p["hi"] for p in instances])
    mask = np.ones(b.shape, dtype=bool)
    return nominal, A, b, mask, lo, hi


def converging_pair(rng, distance, speed):
    """Two agents at ``distance`` (low, high) from a common point, from any angles, heading for
    it at ``speed`` (low, high): positions and velocities (2, 2)."""
    ang = rng.uniform(0, 2 * np.pi)
    ang2 = ang + rng.uniform(-np.pi, np.pi)
    d = rng.uniform(*distance, (2, 1))
    pk = np.array([[np.cos(ang), np.sin(ang)], [np.cos(ang2), np.sin(ang2)]]) * d
    vk = -pk / np.linalg.norm(pk, axis=1, keepdims=True) * rng.uniform(*speed, (2, 1))
    return pk, vk
