"""The high-order CBF of the double integrator (``docs/double_integrator.md``):
``h = |dp|^2 - Ds^2`` with the second-order condition ``h'' + (g1 + g2) h' + g1 g2 h >= 0``,
its pair row split by responsibility (``pair_rows``); continuous time, any input box."""

from __future__ import annotations

from rsvo_env.dynamics.barriers.split import SplitBarrier


class HOCBF(SplitBarrier):
    """The high-order CBF (module docstring), kept for comparison."""

    name = "hocbf"

    def check_box(self, cfg, lo, hi):
        # its rows need no braking: any box is accepted
        return None
