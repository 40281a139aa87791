"""The double integrator's barriers by name: the registry (``docs/architecture.md``). A new
barrier is one module with a subclass of ``Barrier`` plus one line below (or a call of
``register``); ``FilterConfig.barrier`` names one."""

from __future__ import annotations

from rsvo_env.dynamics.barriers.backup import Backup
from rsvo_env.dynamics.barriers.braking import Braking
from rsvo_env.dynamics.barriers.hocbf import HOCBF
from rsvo_env.dynamics.barriers.interface import Barrier
from rsvo_env.dynamics.barriers.pair_rows import SPLITS
from rsvo_env.dynamics.barriers.segment import Segment
from rsvo_env.util.validation import shown

BARRIERS: dict[str, Barrier] = {}

__all__ = ["BARRIERS", "SPLITS", "Barrier", "get", "names", "register"]


def register(barrier: Barrier) -> Barrier:
    """Add ``barrier`` (an instance of a ``Barrier`` subclass) under its ``name``; a name
    taken by another barrier raises."""
    if not isinstance(barrier, Barrier) or not isinstance(barrier.name, str) or not barrier.name:
        raise TypeError(f"register takes a Barrier with a name, got {shown(barrier)}")
    if BARRIERS.get(barrier.name, barrier) != barrier:
        raise ValueError(f"barrier {shown(barrier.name)} is registered already")
    BARRIERS[barrier.name] = barrier
    return barrier


def names() -> tuple[str, ...]:
    """The registered barriers' names, the default (``"segment"``) first."""
    return tuple(BARRIERS)


def get(barrier: str, field: str = "barrier") -> Barrier:
    """The barrier of a name; an unknown name raises naming ``field`` and the names known."""
    if isinstance(barrier, str) and barrier in BARRIERS:
        return BARRIERS[barrier]
    raise ValueError(f"{field} = {shown(barrier)}; use one of {names()}")


# the stopping segment is the default; the backup (the stopping disk), the braking barrier
# (the paper's) and the HOCBF are kept by name for comparison
for _barrier in (Segment(), Backup(), Braking(), HOCBF()):
    register(_barrier)
