"""Scratch arrays numba does not reference count, for the innermost loops of the compiled
stages. Every array numba hands to an inlined function, and every view of one, is counted: an
atomic increment and decrement of its owner's count. Per agent, a solve that hands its rows
down through the inlined linear programs pays five such pairs, a quarter of R-ORCA's time in a
crowd of 16 (measured with perf: ``benchmarks/results/rorca_speed.md``). A view made by
``borrow`` has no owner to count; the array it views must outlive it, which an argument of
the function that borrows it does, where that function is called and not inlined (the caller
holds the argument until the call returns; inlined, the caller's variable may be released after
its last use, the borrow)."""

from __future__ import annotations

from numba import carray, njit, types
from numba.extending import intrinsic


@intrinsic
def _float_pointer(typingctx, address):
    """The integer ``address`` as a ``float64*``."""
    sig = types.CPointer(types.float64)(address)

    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], context.get_value_type(signature.return_type))

    return sig, codegen


@njit(cache=True, inline="always")
def borrow(a):
    """A view of the C-contiguous float64 array ``a`` without a reference count: ``a`` must
    outlive it (borrow only an argument of a function that is not inlined)."""
    return carray(_float_pointer(a.ctypes.data), a.shape)
