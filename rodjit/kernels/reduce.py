"""NaN-propagating min/max that the compiler can vectorise inside reductions.

``min(x, e)`` or ``e if e < x else x`` in a loop is a chain of compare-and-select that
LLVM only vectorises under fast-math (no NaNs assumed), which would also break the NaN
checks downstream.  ``nan_min``/``nan_max`` lower to LLVM's ``llvm.minimum``/``llvm.maximum``
(IEEE 754-2019 minimum/maximum: a NaN operand gives NaN), whose reductions LLVM vectorises
without any fast-math flag.  The result of a min/max reduction does not depend on the
order of evaluation, so vectorising it changes no bits; and a NaN anywhere in the reduced
values shows up in the result, so a single finiteness test of the result covers them all.
"""
import math

from .._jit import overload, when_loaded

__all__ = ["nan_min", "nan_max"]


def nan_min(a, b):
    """The smaller of a, b; NaN if either is NaN."""
    if math.isnan(a) or math.isnan(b):
        return math.nan
    if a == b:  # −0 < +0, as in IEEE minimum
        return a if math.copysign(1.0, a) < 0 else b
    return a if a < b else b


def nan_max(a, b):
    """The larger of a, b; NaN if either is NaN."""
    if math.isnan(a) or math.isnan(b):
        return math.nan
    if a == b:
        return b if math.copysign(1.0, a) < 0 else a
    return a if a > b else b


def _llvm_binary(name):
    from llvmlite import ir
    from numba import types
    from numba.extending import intrinsic

    @intrinsic
    def call(typingctx, a, b):
        sig = types.float64(types.float64, types.float64)

        def codegen(context, builder, signature, args):
            dbl = ir.DoubleType()
            fn = builder.module.declare_intrinsic(name, [dbl], ir.FunctionType(dbl, [dbl, dbl]))
            x = context.cast(builder, args[0], signature.args[0], types.float64)
            y = context.cast(builder, args[1], signature.args[1], types.float64)
            return builder.call(fn, [x, y])

        return sig, codegen

    return call


def _make_intrinsics():
    global _minimum, _maximum
    _minimum = _llvm_binary("llvm.minimum")
    _maximum = _llvm_binary("llvm.maximum")


when_loaded(_make_intrinsics)


def _floats(a, b) -> bool:
    from numba import types

    return isinstance(a, types.Float) and isinstance(b, types.Float)


@overload(nan_min)
def _nan_min_ov(a, b):
    if _floats(a, b):
        return lambda a, b: _minimum(a, b)


@overload(nan_max)
def _nan_max_ov(a, b):
    if _floats(a, b):
        return lambda a, b: _maximum(a, b)
