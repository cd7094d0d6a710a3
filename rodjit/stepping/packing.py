"""How a point's parameter tuples travel into compiled code: one row of doubles.

The compiled loop takes six parameter tuples (scheme, control, system, rod law, floor law,
observer: ``driver.setup.parameters``).  Three callers pass them through an interface that takes
arrays, not tuples: the CPU engine's batch kernel (``stepping.ensemble.run_batch``, many
points in one call), the GPU kernel (``gpu.kernel``, one thread a point) and the exported
functions of the extension compiled ahead of time (``stepping.aot``).  Each gets a point's
tuples as one row of float64 (``pack``) and rebuilds them in compiled code, field by field,
from source written here (``rebuild_source``), so the parameters' values stay run-time
values and one compile serves every point of a *family* (``family``: the tuples' classes
and their fields' types).

A field's *kind* (``kind``) says how it travels:

- ``"f"`` a float, stored as itself and read back as ``row[k]``;
- ``"i"`` an int, stored exactly as a double (``pack`` refuses one of 2**53 or more in
  size, which a double cannot hold exactly) and read back as ``int(row[k])``;
- ``"b"`` a bool, stored as 1.0 or 0.0 and read back as ``row[k] != 0.0``;
- ``"v"`` anything else: not in the row; the family holds its value (its ``repr``) and the
  rebuilt tuple takes it from a prototype tuple of the family (``rebuild``'s ``protos``).

NumPy scalars count as their kind for the CPU engine.  The GPU kernel and the extension
take exact Python floats, ints and bools only (``exact``): their kernels are compiled for
those types, and a field of another type (a ``float32``) would be read back as a float64,
a run on other types than the JIT's.

The extension takes the same single row as the other two rather than its floats and its
ints in two arrays: the ints of the tuples fit a double exactly (checked at ``pack``), and
one row means one layout and one generator of the rebuilding code for all three callers.
"""
from __future__ import annotations

from typing import Callable, Sequence

import numpy as np

from .._jit import overload

__all__ = ["kind", "kinds", "family", "pack", "rebuild_source", "rebuild"]

_EXACT = {float: "f", int: "i", bool: "b"}
INT_LIMIT = 2**53         # an int of a smaller size is a double exactly


def kind(x, exact: bool = False) -> str:
    """The kind of a field value ``x`` (module docstring); ``exact``: only a Python float,
    int or bool has one, anything else is a TypeError."""
    got = _EXACT.get(type(x))
    if got is not None:
        return got
    if exact:
        raise TypeError(f"a parameter field of type {type(x).__name__} has no compiled "
                        f"form here (a float, int or bool)")
    if isinstance(x, (bool, np.bool_)):
        return "b"
    if isinstance(x, (int, np.integer)):
        return "i"
    if isinstance(x, (float, np.floating)):
        return "f"
    return "v"


def kinds(params, exact: bool = False) -> tuple[str, ...]:
    """Per parameter tuple of ``params``, the kinds of its fields as one string."""
    return tuple("".join(kind(x, exact) for x in t) for t in params)


def family(params) -> tuple:
    """What must be equal for points to share a compiled call: the tuples' classes, each
    field's type, and the value of every field that is not packed (kind ``"v"``)."""
    out: list = []
    for t in params:
        out.append(type(t))
        for x in t:
            out.append(type(x) if kind(x) != "v" else ("value", repr(x)))
    return tuple(out)


def pack(params, exact: bool = False) -> list[float]:
    """The packed fields of the tuples ``params``, in order, as one row of doubles: every
    float, int and bool (module docstring); ``exact`` as ``kind``."""
    row = []
    for t in params:
        for x in t:
            k = kind(x, exact)
            if k == "v":
                continue
            if k == "i" and not -INT_LIMIT < int(x) < INT_LIMIT:
                raise ValueError(f"a parameter field of {type(t).__name__} is {x}, not an "
                                 f"int of size below 2**53 that a double holds exactly")
            row.append(float(x))
    return row


def rebuild_source(kinds: Sequence[str], row: str, classes: Sequence[str],
                   value: Callable[[int, int], str] | None = None) -> list[str]:
    """Python source of an expression per parameter tuple that makes it again from the
    packed row named ``row``: the class ``classes[k]`` called with each field read back by
    its kind (``kinds[k]``, module docstring), ``value(k, j)`` the source of the value of a
    field ``j`` of kind ``"v"`` (there is none without it)."""
    out = []
    o = 0
    for k, ks in enumerate(kinds):
        args = []
        for j, c in enumerate(ks):
            if c == "v":
                if value is None:
                    raise TypeError(f"field {j} of {classes[k]} is not a float, int or "
                                    f"bool: it has no packed form")
                args.append(value(k, j))
                continue
            x = f"{row}[{o}]"
            args.append({"f": x, "i": f"int({x})", "b": f"{x} != 0.0"}[c])
            o += 1
        out.append(f"{classes[k]}({', '.join(args)})")
    return out


_MADE: dict = {}


def _function(classes: tuple, ks: tuple):
    """``rebuild`` for tuples of ``classes`` whose fields have the kinds ``ks``: made from
    ``rebuild_source`` once per family, compiled with this file's name (Numba caches an
    implementation by its source file)."""
    got = _MADE.get((classes, ks))
    if got is None:
        names = [f"C{k}" for k in range(len(classes))]
        exprs = rebuild_source(ks, "row", names, lambda k, j: f"protos[{k}][{j}]")
        name = "rebuild_" + "_".join(c.__name__ for c in classes)
        ns = {n: c for n, c in zip(names, classes)}
        ns["__name__"] = __name__
        body = ", ".join(exprs) + ("," if len(exprs) == 1 else "")
        exec(compile(f"def {name}(protos, row):\n    return ({body})\n", __file__, "exec"),
             ns)
        got = _MADE[(classes, ks)] = ns[name]
    return got


def rebuild(protos, row):
    """The parameter tuples of the classes of ``protos`` (a tuple of them, one point of the
    family) with their packed fields from ``row`` (``pack``), the others from ``protos``.
    This Python version runs where Numba is off (NUMBA_DISABLE_JIT=1), on the row as Python
    floats, as the tuples were built."""
    fn = _function(tuple(map(type, protos)), kinds(protos))
    return fn(protos, row.tolist() if isinstance(row, np.ndarray) else row)


@overload(rebuild)
def _rebuild_ov(protos, row):
    from numba.core import types

    def numba_kind(t) -> str:
        if isinstance(t, types.Boolean):
            return "b"
        if isinstance(t, types.Integer):
            return "i"
        if isinstance(t, types.Float):
            return "f"
        return "v"

    classes = tuple(p.instance_class for p in protos.types)
    return _function(classes, tuple("".join(map(numba_kind, p.types)) for p in protos.types))
