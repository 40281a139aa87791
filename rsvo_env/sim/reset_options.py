"""The reset options the core reads (``theta``, ``weighting``), checked before anything changes."""

from __future__ import annotations

import warnings

import numpy as np
from numpy.typing import NDArray

from rsvo_env.responsibility.svo import Weighting, check_weighting
from rsvo_env.sim.view import SimulatorView
from rsvo_env.util.validation import real_array

RESET_OPTIONS = ("theta", "weighting")


def check_options(sim: SimulatorView, options: dict | None) -> tuple[NDArray | None, Weighting]:
    """Theta (E, N) or None, and the weighting, from reset options; other keys are left for
    wrappers (PettingZoo's own API test passes one of its own)."""
    options = options or {}
    unknown = sorted(set(options) - set(RESET_OPTIONS) - sim.warned_options)
    if unknown:
        # not an error: PettingZoo's API test passes an option of its own
        sim.warned_options.update(unknown)
        warnings.warn(
            f"reset options {unknown} are not used by rsvo_env; it reads {list(RESET_OPTIONS)}",
            stacklevel=3,
        )
    theta = None
    if "theta" in options:
        raw = real_array(options["theta"], "theta")
        # exactly (N,) (every env) or (E, N) (one row an env): nothing reshaped or broadcast
        if raw.ndim == 1 and raw.shape != (sim.n,):
            raise ValueError(f"theta has {raw.shape[0]} entries, expected {sim.n}")
        if raw.shape not in ((sim.n,), (sim.num_envs, sim.n)):
            raise ValueError(
                f"theta has shape {raw.shape}, expected ({sim.n},) or ({sim.num_envs}, {sim.n})"
            )
        rows = raw if raw.ndim == 2 else raw[None]
        checked = []
        for e, row in enumerate(rows):
            try:
                checked.append(sim.scenario.check_theta(row))
            except ValueError as exc:
                raise ValueError(f"{exc} (env {e})" if raw.ndim == 2 else str(exc)) from None
        theta = np.broadcast_to(np.stack(checked), (sim.num_envs, sim.n))
    weighting = options.get("weighting", sim.weighting)
    check_weighting(weighting, np.ones(sim.n) if theta is None else theta[0])
    return theta, weighting
