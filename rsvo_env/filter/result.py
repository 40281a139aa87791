"""What the filter decided (``FilterResult``), and the stats of stacked filters."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rsvo_env.qp.rows import Rows


@dataclass(slots=True)
class FilterResult:
    """What the filter decided for each agent (the ``certify_action`` contract: action + flag).

    Per-agent arrays have the input's leading shape, (N, ...) or (E, N, ...); per-scene values
    are scalars for one scene and (E,) arrays for a batch. ``rows`` are every agent's rows; the
    compiled all-pairs pass keeps none, and builds them on first access (the general path on
    the same inputs: the same rows).

    Attributes:
        actions: The certified actions, in the model's inputs.
        feasible: False where an agent's QP had no solution; its action is then the one that
            minimises the largest normalised violation, never the nominal.
        intervention: ``|u - u_nominal|`` of each agent.
        active: How many of each agent's rows bind at its action.
        min_h: The scene's smallest barrier value over its pairs and obstacles.
        max_violation: How far each agent's action breaks its rows (in the units of a
            half-plane's offset; 0 where feasible).
        n_rows: How many rows each agent's QP had.
        n_unrecoverable_pairs: Pairs of the double integrator's split barriers that no action
            in the boxes can recover, per scene.
        n_capped_shares: Pairs whose share the capability split capped, per scene.
        kept_rows: The rows, where the path that solved kept them.
        rows_later: What builds the rows on first access, where none were kept.
    """

    actions: NDArray[np.float64]
    feasible: NDArray[np.bool_]
    intervention: NDArray[np.float64]
    active: NDArray[np.int64]
    min_h: Any
    max_violation: NDArray[np.float64]
    n_rows: NDArray[np.int64]
    n_unrecoverable_pairs: Any
    n_capped_shares: Any
    kept_rows: Rows | None = field(default=None, repr=False)
    rows_later: Callable[[], Rows] | None = field(default=None, repr=False)

    @property
    def rows(self) -> Rows | None:
        """The rows of every agent (None from a simulator's filter stage, which needs none)."""
        if self.kept_rows is None and self.rows_later is not None:
            self.kept_rows, self.rows_later = self.rows_later(), None
        return self.kept_rows

    def squeeze(self) -> FilterResult:
        """The single-scene result of a batch of one."""
        return FilterResult(
            actions=self.actions[0],
            feasible=self.feasible[0],
            intervention=self.intervention[0],
            active=self.active[0],
            min_h=float(self.min_h[0]),
            max_violation=self.max_violation[0],
            n_rows=self.n_rows[0],
            n_unrecoverable_pairs=int(self.n_unrecoverable_pairs[0]),
            n_capped_shares=int(self.n_capped_shares[0]),
            kept_rows=self.kept_rows,
            rows_later=self.rows_later,
        )


def per_env(env: NDArray[np.int64], flags: NDArray[np.bool_], E: int) -> NDArray[np.int64]:
    """(E,) how many of the rows of each env are flagged."""
    return np.bincount(env[flags], minlength=E).astype(np.int64)


def merge_stats(stats: dict[str, Any] | None, res: FilterResult) -> dict[str, Any]:
    """The filter stage's stats after one more stacked filter: feasible only if every filter
    was, the largest violation, counts summed, the smallest barrier; ``active`` the last's."""
    if stats is None:
        return {
            "feasible": res.feasible,
            "max_violation": res.max_violation,
            "n_unrecoverable_pairs": res.n_unrecoverable_pairs,
            "n_capped_shares": res.n_capped_shares,
            "min_h": res.min_h,
            "active": res.active,
        }
    return {
        "feasible": stats["feasible"] & res.feasible,
        "max_violation": np.maximum(stats["max_violation"], res.max_violation),
        "n_unrecoverable_pairs": stats["n_unrecoverable_pairs"] + res.n_unrecoverable_pairs,
        "n_capped_shares": stats["n_capped_shares"] + res.n_capped_shares,
        "min_h": np.minimum(stats["min_h"], res.min_h),
        "active": res.active,
    }
