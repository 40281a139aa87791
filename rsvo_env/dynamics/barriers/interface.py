"""The barrier interface of the double integrator (``docs/double_integrator.md``): what the
filter asks of a barrier, whatever its safe set. A new barrier is one module with a subclass of
``Barrier`` plus one line in the registry (``rsvo_env.dynamics.barriers``)."""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numpy.typing import NDArray

from rsvo_env.util.validation import shown

if TYPE_CHECKING:
    from rsvo_env.geometry.bodies import Bodies
    from rsvo_env.qp.rows import Rows
    from rsvo_env.util.settings import FilterSettings


class Barrier:
    """A barrier ``h`` of the double integrator and its rows: every agent's half-planes
    ``A a <= b`` (its share of each pair's condition, split by the responsibility weights
    ``omega``, and weight 1 against each obstacle), the distance beyond which none of them can
    bind, and what it needs of the input box. Stateless: one instance serves every filter.

    ``backed``: every agent has one action (its backup) that meets all its rows at once while
    every ``h >= 0``, so every QP is feasible, walls included, at any ``dt``.
    """

    name: ClassVar[str] = ""
    backed: ClassVar[bool] = False

    def check_box(self, cfg: FilterSettings, lo: NDArray, hi: NDArray) -> None:
        """Refuse an input box (``lo``, ``hi`` (2,)) under which the barrier's guarantee does
        not hold; braking needs ``u_min < 0 < u_max``."""
        if not ((lo < 0).all() and (hi > 0).all()):
            raise ValueError(
                f"FilterConfig: the {self.name} barrier needs u_min < 0 < u_max, got "
                f"u_min = {shown(lo.tolist())}, u_max = {shown(hi.tolist())}"
            )

    def filter_rows(
        self,
        cfg: FilterSettings,
        positions: NDArray,
        velocities: NDArray,
        weights: NDArray,
        I: NDArray,
        J: NDArray,
        bodies: Bodies,
        capsules: NDArray | None,
        n: int,
    ) -> tuple[Rows, NDArray | None]:
        """Every agent's rows, stored by agent, for the pairs (``I``, ``J``: flat agent indices;
        ``weights`` (P, 2) each pair's ``omega_ij``, ``omega_ji``) and the obstacles
        ``capsules`` ((E, O, 5) or (1, O, 5), ``n`` agents an env; None: none), with ``positions``
        and ``velocities`` (M, 2) and each agent's body and box (``bodies``). Returns the rows and
        each agent's smallest h against the obstacles (None without)."""
        raise NotImplementedError

    def culling_radii(
        self,
        cfg: FilterSettings,
        omega_floor: NDArray,
        velocities: NDArray,
        bodies: Bodies,
    ) -> NDArray[np.float64]:
        """Per agent and weight floor ``omega_floor`` (E, N, K), the distance beyond which
        none of its rows with a weight of at least the floor can bind, given the
        ``velocities`` (E, N, 2) and ``bodies``."""
        raise NotImplementedError

    def h(
        self,
        cfg: FilterSettings,
        positions: NDArray,
        velocities: NDArray,
        I: NDArray,
        J: NDArray,
        bodies: Bodies,
    ) -> NDArray[np.float64]:
        """The safe-set value ``h`` of each pair (``I``, ``J``) (P,): the pair is in the
        barrier's safe set where ``h >= 0``."""
        weights = np.full((len(I), 2), 0.5)
        rows, _ = self.filter_rows(cfg, positions, velocities, weights, I, J, bodies, None, 0)
        return rows.pair_h

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"
