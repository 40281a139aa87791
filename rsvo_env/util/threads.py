"""How many threads the library's compiled kernels use (``docs/threads.md``).

One by default. A parallel kernel (numba's OpenMP or TBB pool) pays only while its threads have
cores: where several processes share few cores, as SB3's ``SubprocVecEnv``, Ray's env runners,
``pytest -n`` and sweeps do, each launch waits for workers that other processes' threads hold,
and the step becomes many times slower than one thread's (``benchmarks/results/contention.md``).
One thread cannot stall, and the library's throughput tables are measured with one. A process
that has its cores to itself opts in: ``RSVO_NUM_THREADS=2`` in the environment, or
``set_num_threads`` (``using`` for a block). Kernels then run in parallel over at least
``sizes.PARALLEL_MIN_PROBLEMS`` independent problems, below which a launch costs more than it
saves.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import numba
import numpy as np

from rsvo_env.util import sizes
from rsvo_env.util.validation import shown

ENV_VAR = "RSVO_NUM_THREADS"
# the sizes at which a kernel changes form: sizes.PARALLEL_MIN_PROBLEMS (several threads) and
# sizes.PRANGE_FORM_MIN_AGENTS (the prange form on one thread), measured there


def _checked(value: object, name: str) -> int:
    """A thread count: an integer from 1 to numba's pool size (``NUMBA_NUM_THREADS``)."""
    limit = numba.config.NUMBA_NUM_THREADS
    if isinstance(value, str):
        try:
            value = int(value.strip())
        except ValueError:
            raise ValueError(f"{name} = {shown(value)} is not an integer thread count") from None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} = {shown(value)} must be an integer thread count")
    n = int(value)
    if not 1 <= n <= limit:
        raise ValueError(f"{name} = {n} must be from 1 to numba's pool size, {limit}")
    return n


_threads = _checked(os.environ.get(ENV_VAR, "1"), ENV_VAR)


def get_num_threads() -> int:
    """The threads the library's kernels use (1 unless opted in)."""
    return _threads


def set_num_threads(n: int) -> None:
    """Let the library's kernels use ``n`` threads (1: serial kernels only). Raises
    ``ValueError`` naming the value unless ``1 <= n <= NUMBA_NUM_THREADS``."""
    global _threads
    _threads = _checked(n, "threads")


@contextmanager
def using(n: int) -> Iterator[None]:
    """``n`` threads for the kernels within the block, the previous count after it."""
    before = _threads
    set_num_threads(n)
    try:
        yield
    finally:
        set_num_threads(before)


def parallel(work: int) -> bool:
    """The one rule for running in parallel: opted in, and at least
    ``sizes.PARALLEL_MIN_PROBLEMS`` independent problems (``work``). It sets nothing: ``launch``
    sets numba's count for the launch and puts the caller's back."""
    return _threads > 1 and work >= sizes.PARALLEL_MIN_PROBLEMS


def launch(serial: Callable, prange: Callable, work: int, *args: Any) -> Any:
    """Call the form of a kernel that pays over ``work`` agents: its ``prange`` form on the
    library's threads in parallel (``parallel``'s rule) or on one thread from
    ``sizes.PRANGE_FORM_MIN_AGENTS`` agents (faster than the plain loop there), else ``serial``.
    numba's thread count for the calling thread, which a user's own kernels read, is set for
    the launch only and put back after it."""
    n = _threads if parallel(work) else int(work >= sizes.PRANGE_FORM_MIN_AGENTS)
    if not n:
        return serial(*args)
    caller = numba.get_num_threads()
    if caller == n:
        return prange(*args)
    numba.set_num_threads(n)
    try:
        return prange(*args)
    finally:
        numba.set_num_threads(caller)
