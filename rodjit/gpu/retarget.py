"""One source of the model for two targets: rodjit's CPU kernels recompiled for CUDA.

The laws, forces, integrators, event tracking and the time loop are plain Python functions
that the CPU compiles through ``rodjit._jit`` (a ``Kernel`` keeps its function as
``py_func``).  ``Retarget`` compiles the *same functions* for the GPU: for each one it makes
a copy of the function object (the same code object, so the same bytecode and constants)
whose global names and closure cells are mapped to their GPU counterparts, and compiles
that copy with ``cuda.jit(device=True)``:

- a ``Kernel`` -> the device function of its ``py_func`` (recursively, made once);
- a function with a compile-time dispatch (``_jit.overload``: the generic law functions
  ``value``/``deriv``/..., the scheme's ``initial``/``step``, the loop's side rules) -> a
  stub with a CUDA-target ``numba.extending.overload`` that calls the *same* typing
  implementation (``_jit.OVERLOADS``) and retargets the implementation it returns;
- a rodjit module used by attribute (``control as C``, ``layout as L``) -> a proxy module
  whose attributes are mapped the same way;
- ``numpy`` -> a proxy that is NumPy except the scalar ufuncs that numba-cuda does not
  lower (``np.cbrt``, ``np.sqrt``, ``np.exp``, ...: ``_scalar_functions``), which become
  the same functions of libdevice or ``math`` (``sqrt`` correctly rounded, as the CPU's;
  the kernels' one ``cbrt`` is a first step proposal).

Nothing of the model is written twice.  A law registered from outside is retargeted the
same way; one whose functions do something CUDA cannot compile is refused when its kernel
is compiled (``engine`` says so in one line).

Numerics: the CPU compiles with fused multiply-adds allowed (``_jit``), and so does NVVM
by default; the two compilers fuse different pairs, so the GPU's results agree with the
CPU's to rounding, not bit for bit.
"""
from __future__ import annotations

import types

import numpy as np

from .._jit import OVERLOADS, Kernel

__all__ = ["Retarget"]


def _names(code) -> set[str]:
    """Global names a code object (and the code objects nested in it) may read."""
    out = set(code.co_names)
    for c in code.co_consts:
        if isinstance(c, types.CodeType):
            out |= _names(c)
    return out


def _cell(value):
    return (lambda: value).__closure__[0]


class Retarget:
    """Maps rodjit's compiled functions to CUDA device functions (module docstring).
    One instance per compiled kernel family: what it made is kept, so each function is
    retargeted once however many callers it has."""

    def __init__(self, cuda):
        self.cuda = cuda
        self._devices: dict[int, object] = {}
        self._copies: dict[int, types.FunctionType] = {}
        self._stubs: dict[int, object] = {}
        self._modules: dict[str, types.ModuleType] = {}
        self._keep: list = []     # the originals, so their ids stay unique
        self._numpy = None

    # ---- values a retargeted function reads ------------------------------------------
    def value(self, v):
        """The GPU counterpart of a global or closure value (module docstring)."""
        if isinstance(v, Kernel):
            return self.device(v.py_func)
        if isinstance(v, types.FunctionType) and v in OVERLOADS:
            return self.stub(v)
        if isinstance(v, types.ModuleType):
            if v is np:
                return self.numpy()
            if v.__name__.startswith("rodjit."):
                return self.module(v)
        return v

    def function(self, f):
        """A copy of the Python function ``f`` reading GPU counterparts (not compiled)."""
        f = getattr(f, "py_func", f)
        got = self._copies.get(id(f))
        if got is not None:
            return got
        g: dict = {"__builtins__": f.__globals__.get("__builtins__", __builtins__)}
        closure = None
        if f.__closure__:
            closure = tuple(_cell(self.value(c.cell_contents)) for c in f.__closure__)
        copy = types.FunctionType(f.__code__, g, f.__name__, f.__defaults__, closure)
        copy.__qualname__ = f.__qualname__
        copy.__module__ = f.__module__
        copy.__doc__ = f.__doc__
        self._copies[id(f)] = copy
        self._keep.append(f)
        # filled after the copy is registered: a function reached again on the way (a
        # recursion) gets the same copy
        for name in _names(f.__code__):
            if name in f.__globals__:
                g[name] = self.value(f.__globals__[name])
        return copy

    def device(self, f):
        """The CUDA device function compiled from ``f``'s retargeted copy."""
        f = getattr(f, "py_func", f)
        got = self._devices.get(id(f))
        if got is None:
            got = self._devices[id(f)] = self.cuda.jit(device=True)(self.function(f))
        return got

    def stub(self, generic):
        """A stand-in for ``generic`` with its compile-time dispatch on the CUDA target."""
        got = self._stubs.get(id(generic))
        if got is not None:
            return got
        from numba.extending import overload

        typer = OVERLOADS[generic]
        stub = types.FunctionType(generic.__code__, {}, generic.__name__, generic.__defaults__,
                                  generic.__closure__)
        self._stubs[id(generic)] = stub
        self._keep.append(generic)

        def cuda_typer(*args, **kwargs):
            impl = typer(*args, **kwargs)
            return None if impl is None else self.function(impl)

        overload(stub, target="cuda", strict=False)(cuda_typer)
        return stub

    def module(self, mod):
        """A proxy of a rodjit module: its attributes mapped by ``value`` on first use."""
        got = self._modules.get(mod.__name__)
        if got is None:
            got = types.ModuleType(f"{mod.__name__}[cuda]")
            cache: dict = {}

            def attr(name, mod=mod, cache=cache):
                if name.startswith("__"):
                    raise AttributeError(name)
                if name not in cache:
                    cache[name] = self.value(getattr(mod, name))
                return cache[name]

            got.__getattr__ = attr
            self._modules[mod.__name__] = got
        return got

    def numpy(self):
        """NumPy with its scalar ufuncs that numba-cuda does not lower replaced by the
        same functions of ``math`` or libdevice (module docstring)."""
        if self._numpy is None:
            cuda = self.cuda
            proxy = types.ModuleType("numpy[cuda]")
            for name, fn in _scalar_functions(cuda).items():
                setattr(proxy, name, cuda.jit(device=True)(_calling(fn)))
            proxy.__getattr__ = lambda name: getattr(np, name)
            self._numpy = proxy
        return self._numpy


def _calling(fn):
    def call(x):
        return fn(x)
    return call


def _scalar_functions(cuda) -> dict:
    """NumPy's name -> the function a device function computes it with, for the scalar
    ufuncs that the kernels and laws may call: libdevice's ``sqrt`` (correctly rounded, as
    the CPU's) and ``cbrt``, ``math``'s others (libdevice's, within their ulp bounds)."""
    import math

    lib = cuda.libdevice
    out = {"sqrt": lib.sqrt, "cbrt": lib.cbrt, "abs": abs, "absolute": abs,
           "fabs": math.fabs, "arctan": math.atan, "arcsin": math.asin,
           "arccos": math.acos, "arctanh": math.atanh, "arcsinh": math.asinh}
    for name in ("exp", "expm1", "log", "log1p", "log2", "log10", "sin", "cos", "tan",
                 "sinh", "cosh", "tanh", "floor", "ceil"):
        out[name] = getattr(math, name)
    return out
