"""Views of arrays that skip Numba's reference counting, for the inner time loop.

Numba counts references to every array with atomic increments and decrements: each view
(``state[0]``) and each array passed to a function that is not inlined costs a few of
them.  The time loop hands ~10 arrays to the step, the forces and the event tracking on
every step, which cost ~30 atomic pairs, ~0.4 µs per step: more than a whole step of a
short rod, and a third of a step at N = 1000 (benchmarks/bench_explicit.py).

``borrow(a)`` returns the same array (same data, shape, strides) with no owner record
(a NULL meminfo): Numba's reference counting skips such arrays, and views made from them
inherit that.  The caller must keep the original alive while the borrowed view is used,
and must not return or store it: ``advance`` borrows its own arguments, which the caller
holds for the whole call, and uses them only inside the call.

Called from Python (or with NUMBA_DISABLE_JIT=1), ``borrow`` returns its argument.
"""
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic, overload

from .._jit import JIT_OPTIONS
from numba.np.arrayobj import make_array

__all__ = ["borrow"]


def borrow(a):
    """``a`` itself, seen by compiled code as an unowned view (see the module docstring)."""
    return a


@intrinsic
def _unowned(typingctx, a):
    if not isinstance(a, types.Array):
        return None

    def codegen(context, builder, sig, args):
        src = make_array(a)(context, builder, value=args[0])
        dst = make_array(a)(context, builder)
        dst.meminfo = cgutils.get_null_value(dst.meminfo.type)
        dst.parent = cgutils.get_null_value(dst.parent.type)
        dst.nitems = src.nitems
        dst.itemsize = src.itemsize
        dst.data = src.data
        dst.shape = src.shape
        dst.strides = src.strides
        return dst._getvalue()   # a new value, owning nothing: no incref

    return a(a), codegen


@overload(borrow, jit_options=JIT_OPTIONS)
def _borrow_ov(a):
    if isinstance(a, types.Array):
        return lambda a: _unowned(a)
