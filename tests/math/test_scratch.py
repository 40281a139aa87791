"""``rsvo_env.util.scratch``: a borrowed view is the owner's memory, with its shape, and the
compiled stages that borrow their scratch give the velocities the counted arrays gave (the
R-ORCA tests compare them bit for bit with the pair-by-pair reference)."""

import numpy as np
from numba import njit

from rsvo_env.util.scratch import borrow


@njit
def _write_through(owner, value):
    view = borrow(owner)
    for i in range(view.shape[0]):
        for k in range(view.shape[1]):
            view[i, k] = value * (3 * i + k)
    return view.shape[0], view.shape[1], view[view.shape[0] - 1, view.shape[1] - 1]


def test_a_borrowed_view_reads_and_writes_its_owner():
    owner = np.zeros((5, 3))
    rows, cols, last = _write_through(owner, 0.5)
    assert (rows, cols) == owner.shape
    assert np.array_equal(owner, 0.5 * np.arange(15.0).reshape(5, 3))
    assert last == owner[-1, -1]
