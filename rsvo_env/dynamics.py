"""Agent dynamics, integrated exactly under a zero-order hold (input constant over a step).

Single integrator (paper, Sec. III-B): ``x' = u``. Double integrator (paper, eq. ``dynamics``):
``p' = v``, ``v' = a``. Both are linear, so the zero-order-hold step is exact.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def single_integrator_step(
    x: NDArray[np.float64], u: NDArray[np.float64], dt: float
) -> NDArray[np.float64]:
    """``x+ = x + dt u``."""
    return x + dt * u


def double_integrator_step(
    p: NDArray[np.float64], v: NDArray[np.float64], a: NDArray[np.float64], dt: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``p+ = p + dt v + dt^2/2 a``, ``v+ = v + dt a``."""
    return p + dt * v + (0.5 * dt * dt) * a, v + dt * a
