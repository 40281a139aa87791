"""Each agent's own size and input limits, as the filter sees them: flat arrays over E x N
agents (agent ``e * N + i`` is agent i of env e, as in the pair lists).

A pair is safe at distance ``r_i + r_j`` (its body radii); a scalar ``safety_radius`` keeps its
meaning, the pair distance of identical agents (each a body of radius ``safety_radius / 2``).
Each agent's QP has its own box ``lo_i <= u <= hi_i``; ``u_max`` per agent is the box
``[-u_max_i, u_max_i]`` in each component.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rsvo_env.util.validation import real_array, shown

if TYPE_CHECKING:
    from rsvo_env.util.settings import FilterSettings


def check_per_agent(values: ArrayLike, name: str, lead: tuple[int, ...]) -> NDArray[np.float64]:
    """One finite number > 0 per agent, shape ``lead`` ((N,) or (E, N)); the error names the
    field, the env (when batched), the agent and the value."""
    arr = real_array(values, name)
    if arr.shape != lead:
        raise ValueError(f"{name} has shape {arr.shape}, expected {lead} (one per agent)")
    bad = ~np.isfinite(arr) | (arr <= 0)
    if bad.any():
        idx = tuple(int(k) for k in np.argwhere(bad)[0])
        env = f"env {idx[0]}, " if len(idx) == 2 else ""
        where = "".join(f"[{k}]" for k in idx)
        raise ValueError(
            f"{name}{where} = {shown(float(arr[idx]))} must be a finite number > 0 "
            f"({env}agent {idx[-1]})"
        )
    return arr


@dataclass(frozen=True)
class Bodies:
    """Body radii (M,), input boxes ``lo``, ``hi`` (M, 2) and each env's largest radius (E,)
    for M = E * N agents; ``uniform``: every agent has the config's radius and box."""

    radii: NDArray[np.float64]
    lo: NDArray[np.float64]
    hi: NDArray[np.float64]
    r_max: NDArray[np.float64]
    uniform: bool
    # (M,) each agent's largest input vector |max(|lo|, |hi|)| (the box's far corner)
    speed: NDArray[np.float64]
    # (M,) the unicycle's look-ahead distance of each agent, 0 for a holonomic agent (a single
    # integrator in a mixed crowd); None: the config's for every agent
    lookahead: NDArray[np.float64] | None = None
    # (M,) each agent's own input bound as given (u_max per agent), None: the config's
    limits: NDArray[np.float64] | None = None

    @classmethod
    def of(
        cls,
        cfg: FilterSettings,
        E: int,
        n: int,
        radii: NDArray | None = None,
        u_max: NDArray | None = None,
    ) -> Bodies:
        """The bodies of E envs x N agents: ``radii`` and ``u_max`` (E, N) already checked, or
        None for the config's (``safety_radius / 2``, the box ``cfg.lo``, ``cfg.hi``)."""
        M = E * n
        if radii is None:
            r = np.full(M, 0.5 * cfg.safety_radius)
        else:
            r = np.ascontiguousarray(radii, dtype=np.float64).reshape(M)
        limits = None
        if u_max is None:
            lo, hi = np.tile(cfg.lo, (M, 1)), np.tile(cfg.hi, (M, 1))
        else:
            limits = np.asarray(u_max, dtype=np.float64).reshape(M)
            lo, hi = cfg.model.agent_boxes(cfg, limits)
        r_max = r.reshape(E, n).max(axis=1) if n else np.zeros(E)
        made = cls.made(r, lo, hi, r_max, radii is None and u_max is None)
        return made if limits is None else replace(made, limits=limits)

    @classmethod
    def made(
        cls, radii: NDArray, lo: NDArray, hi: NDArray, r_max: NDArray, uniform: bool
    ) -> Bodies:
        """From the arrays, ``speed`` derived, every array read-only (a filter keeps its
        default bodies from call to call)."""
        c = np.maximum(np.abs(lo), np.abs(hi))
        arrays = [np.ascontiguousarray(a, dtype=np.float64) for a in (radii, lo, hi, r_max)]
        arrays.append(np.hypot(c[:, 0], c[:, 1]))
        for a in arrays:
            a.flags.writeable = False
        r, lo_, hi_, rm, sp = arrays
        return cls(r, lo_, hi_, rm, uniform, sp)

    def with_holonomic(self, holonomic: NDArray, v_max: float, lookahead: float) -> Bodies:
        """A mixed crowd of unicycles: agents flagged ``holonomic`` (M,) are single integrators
        with the box ``[-v_max, v_max]`` per component (their own bound when they have one) and
        look-ahead 0."""
        h = holonomic[:, None]
        v = v_max if self.limits is None else self.limits[:, None]
        lo = np.where(h, -v, self.lo)
        hi = np.where(h, v, self.hi)
        made = Bodies.made(self.radii, lo, hi, self.r_max, False)
        return replace(made, lookahead=np.where(holonomic, 0.0, lookahead), limits=self.limits)

    def reach(self, E: int, n: int) -> NDArray[np.float64]:
        """(E, N) the largest safe distance of each agent's pairs, ``r_i + max_j r_j``."""
        return self.radii.reshape(E, n) + self.r_max[:, None]

    def pair_distance(self, I: NDArray, J: NDArray) -> NDArray[np.float64]:
        """(P,) the safe distance ``r_i + r_j`` of the pairs (I, J)."""
        return self.radii[I] + self.radii[J]
