"""Static obstacles: circles ``(x, y, r)`` and wall segments ``((x0, y0), (x1, y1))`` of a
thickness, all held as capsules (a segment and a radius: a circle is a segment of length 0, a
wall's radius half its thickness).

An obstacle takes no responsibility: agent i's row against it carries weight 1
(``docs/obstacles.md``). For the single integrator, with ``c`` the point of the obstacle's
segment nearest to ``x_i`` and ``R = r_i + rho``: ``h = |x_i - c|^2 - R^2``,
``-2 (x_i - c) . u <= gamma h``. The squared distance to a segment is convex with gradient
``2 (x - c)``, so ``h+ >= h + dt grad h . u >= (1 - gamma dt) h``, and ``u = 0`` meets every row
while ``h >= 0``, as for a pair of agents.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from rsvo_env.qp.rows import storage, support
from rsvo_env.util.validation import real_array, shown


def _table(values: ArrayLike | None, name: str, width: int, what: str) -> NDArray[np.float64]:
    """(K, width) finite reals, or (0, width) for None or an empty list."""
    if values is None:
        return np.zeros((0, width))
    arr = real_array(values, name)
    if arr.size == 0:
        return np.zeros((0, width))
    arr = arr.reshape(len(arr), -1) if arr.ndim >= 2 else arr.reshape(1, -1)
    if arr.shape[1] != width:
        raise ValueError(f"{name} has shape {np.shape(values)}: each entry is {what}")
    bad = ~np.isfinite(arr).all(axis=1)
    if bad.any():
        k = int(np.argmax(bad))
        raise ValueError(f"{name}[{k}] = {arr[k].tolist()} is not finite")
    return arr


@dataclass(frozen=True)
class Obstacles:
    """Static obstacles as capsules: circles and walls of a thickness, in the units of the
    agents' positions. Build them with ``of``.

    Attributes:
        capsules: (O, 5) segment ends ``x0, y0, x1, y1`` and radius ``rho`` (a circle is a
            segment of length 0), circles first, then walls, in the order given; or (E, O, 5),
            one set an env.
    """

    capsules: NDArray[np.float64]

    @classmethod
    def of(
        cls,
        circles: ArrayLike | None = None,
        walls: ArrayLike | None = None,
        thickness: ArrayLike = 0.0,
    ) -> Obstacles:
        """Obstacles from circles and walls.

        Args:
            circles: (C, 3) rows ``x, y, r`` with ``r > 0``; None: none.
            walls: (W, 2, 2) each wall's two ends; None: none.
            thickness: The walls' radius (half their thickness), one number or one per wall,
                >= 0.

        Returns:
            The obstacles, circles first.

        Raises:
            ValueError: A bad value, naming the field, the obstacle and the value.
        """
        c = _table(circles, "circles", 3, "(x, y, r)")
        bad = c[:, 2] <= 0
        if bad.any():
            k = int(np.argmax(bad))
            raise ValueError(
                f"circles[{k}] has radius {shown(float(c[k, 2]))}: an obstacle's radius must be > 0"
            )
        w = _table(walls, "walls", 4, "((x0, y0), (x1, y1))")
        t = real_array(thickness, "thickness")
        if t.shape not in ((), (len(w),)):
            raise ValueError(f"thickness has shape {t.shape}: give one number or one per wall")
        t = np.broadcast_to(t, (len(w),))
        bad = ~np.isfinite(t) | (t < 0)
        if bad.any():
            k = int(np.argmax(bad))
            raise ValueError(
                f"thickness[{k}] = {shown(float(t[k]))} must be finite and >= 0 (wall {k})"
            )
        caps = np.concatenate(
            [np.c_[c[:, :2], c[:, :2], c[:, 2]], np.c_[w, 0.5 * t]], axis=0
        ).reshape(-1, 5)
        return cls(np.ascontiguousarray(caps))

    def __len__(self) -> int:
        return self.capsules.shape[-2]

    def clearance(self, positions: NDArray, radii: NDArray | float = 0.0) -> NDArray[np.float64]:
        """Each body's distance to the nearest obstacle surface, ``|x - c| - rho - r``.

        Args:
            positions: The bodies' centres, (N, 2) or (E, N, 2) (the latter where the capsules
                are one set an env).
            radii: The bodies' radii, one number or one per body.

        Returns:
            (..., N) the clearances (inf without obstacles; negative: overlapping).
        """
        x = np.asarray(positions, dtype=np.float64)
        if len(self) == 0:
            return np.full(x.shape[:-1], np.inf) - radii
        caps = self.capsules
        if caps.ndim == 3 and x.ndim == 2:
            raise ValueError("obstacles of one set an env need positions (E, N, 2)")
        c = nearest_points(x, caps)  # (..., N, O, 2)
        d = np.linalg.norm(x[..., None, :] - c, axis=-1) - caps[..., None, :, 4]
        return d.min(axis=-1) - radii

    def contains(self, positions: NDArray, radii: NDArray | float) -> NDArray[np.bool_]:
        """Which bodies overlap an obstacle (the barrier ``h < 0``).

        Args:
            positions: The bodies' centres, (N, 2) or (E, N, 2).
            radii: The bodies' radii, one number or one per body.

        Returns:
            (..., N) True where a body overlaps an obstacle.
        """
        return self.clearance(positions, radii) < 0


def nearest_points(x: NDArray, capsules: NDArray) -> NDArray[np.float64]:
    """(..., N, O, 2) the point of each capsule's segment nearest to each of x (..., N, 2);
    ``capsules`` (O, 5) or (E, O, 5) with x (E, N, 2)."""
    p0, p1 = capsules[..., None, :, 0:2], capsules[..., None, :, 2:4]
    seg = p1 - p0
    L2 = (seg**2).sum(-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(L2 > 0, ((x[..., :, None, :] - p0) * seg).sum(-1) / L2, 0.0)
    return p0 + np.clip(s, 0.0, 1.0)[..., None] * seg


@njit(cache=True, inline="always")
def nearest_point(px, py, x0, y0, x1, y1):
    """The point of segment (x0, y0)-(x1, y1) nearest to (px, py)."""
    sx, sy = x1 - x0, y1 - y0
    L2 = sx * sx + sy * sy
    s = 0.0
    if L2 > 0.0:
        s = min(max(((px - x0) * sx + (py - y0) * sy) / L2, 0.0), 1.0)
    return x0 + s * sx, y0 + s * sy


@njit(cache=True, inline="always")
def _row(x, radii, caps, m, e, o):
    """Agent m's row against obstacle o of env e: (ax, ay, h) with ``A = -2 (x - c)``."""
    c = caps[e, o]
    cx, cy = nearest_point(x[m, 0], x[m, 1], c[0], c[1], c[2], c[3])
    dx, dy = x[m, 0] - cx, x[m, 1] - cy
    R = radii[m] + c[4]
    return -2.0 * dx, -2.0 * dy, (dx * dx + dy * dy) - R * R


@njit(cache=True)
def single_integrator_obstacle_rows(x, radii, caps, n, gamma, lo, hi, cull):
    """Every agent's rows against every obstacle of its env (module docstring), culled against
    its box, stored by agent. ``x`` (M, 2) flat agents, N = ``n`` an env; ``caps`` (E, O, 5),
    or (1, O, 5) shared by every env. Returns offsets (M + 1,), A (R, 2), b (R,), h (R,), the
    obstacle of each row (R,), and each agent's smallest h over all its obstacles (M,)."""
    M, O = x.shape[0], caps.shape[1]
    shared = caps.shape[0] == 1
    offsets = np.zeros(M + 1, dtype=np.int64)
    min_h = np.full(M, np.inf)
    keep = np.zeros((M, O), dtype=np.bool_)
    for m in range(M):
        e = 0 if shared else m // n
        for o in range(O):
            ax, ay, h = _row(x, radii, caps, m, e, o)
            min_h[m] = min(min_h[m], h)
            binds = gamma * h < support(ax, ay, lo[m, 0], lo[m, 1], hi[m, 0], hi[m, 1])
            if binds or not cull:
                keep[m, o] = True
                offsets[m + 1] += 1
    for m in range(M):
        offsets[m + 1] += offsets[m]
    A, b, hh, which, _, _ = storage(offsets[M])
    k = 0
    for m in range(M):
        e = 0 if shared else m // n
        for o in range(O):
            if keep[m, o]:
                ax, ay, h = _row(x, radii, caps, m, e, o)
                A[k, 0], A[k, 1], b[k], hh[k], which[k] = ax, ay, gamma * h, h, o
                k += 1
    return offsets, A, b, hh, which, min_h
