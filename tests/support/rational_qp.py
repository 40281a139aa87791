"""Ground truth for 2-D QPs in exact rational arithmetic, the arbiter where clarabel (an
interior-point solver, accurate to its tolerances) and the exact solver disagree."""

import itertools
from fractions import Fraction as F

import numpy as np


def exact_qp(nom, A, b, lo, hi):
    """Exact projection in rationals: best feasible candidate among the nominal, projections on
    each line, and pairwise intersections (box edges as lines too)."""
    rows = [(F(a[0]), F(a[1]), F(bb)) for a, bb in zip(A, b, strict=True)]
    rows += [
        (F(1), F(0), F(hi[0])),
        (F(-1), F(0), F(-lo[0])),
        (F(0), F(1), F(hi[1])),
        (F(0), F(-1), F(-lo[1])),
    ]
    n = (F(nom[0]), F(nom[1]))

    def ok(p):
        return all(ax * p[0] + ay * p[1] <= bb for ax, ay, bb in rows)

    cands = [n]
    for ax, ay, bb in rows:
        s = (ax * n[0] + ay * n[1] - bb) / (ax * ax + ay * ay)
        cands.append((n[0] - s * ax, n[1] - s * ay))
    for (a1, b1, c1), (a2, b2, c2) in itertools.combinations(rows, 2):
        det = a1 * b2 - a2 * b1
        if det != 0:
            cands.append(((c1 * b2 - c2 * b1) / det, (a1 * c2 - a2 * c1) / det))
    feas = [p for p in cands if ok(p)]
    if not feas:
        return None
    best = min(feas, key=lambda p: (p[0] - n[0]) ** 2 + (p[1] - n[1]) ** 2)
    return np.array([float(best[0]), float(best[1])])
