"""Who benefits the most? Per agent over the random personality sets of the circular game: the
egoists' and the altruists' deviation from the nominal, path length and arrival step."""

from __future__ import annotations

from typing import Any

import numpy as np

MEASURES = ("deviation from nominal [m]", "path length [m]", "arrival step")


def study(circular: dict[str, Any]) -> dict[str, tuple[float, float, float, float, float]]:
    """Per measure: egoists' mean and median, altruists' mean and median, and the rank
    correlation with theta. The three agents of a set with the smallest theta are its egoists."""
    theta = np.array(circular["sets"])
    per_set = circular["per_set"]
    values = {
        MEASURES[0]: np.array([o["deviation"] for o in per_set]),
        MEASURES[1]: np.array([o["path_length"] for o in per_set]),
        MEASURES[2]: np.array(
            [np.where(o["arrival"] >= 0, o["arrival"], o["steps"]) for o in per_set], dtype=float
        ),
    }
    egoist = theta < np.median(theta, axis=1, keepdims=True)
    result = {}
    for name, v in values.items():
        e, a = v[egoist], v[~egoist]
        rho = float(
            np.corrcoef(np.argsort(np.argsort(theta.ravel())), np.argsort(np.argsort(v.ravel())))[
                0, 1
            ]
        )
        result[name] = (e.mean(), float(np.median(e)), a.mean(), float(np.median(a)), rho)
    return result
