"""The compiled loop of the built-in default run, and the sweeps' batch kernel for the
same types, compiled ahead of time at install.

Numba compiles ``loop.start`` and ``loop.advance`` the first time a process calls them:
about half a minute for the default integrator on a fresh install, and a later process,
which loads them from Numba's disk cache, still pays Numba's own start-up (its import,
typing and target machinery, about a second here) before its first step.  So ``pip install``
builds, where it can, an extension module ``rodjit.stepping._aot_loop``: the two functions
and the batch kernel of the sweeps' ensemble engine (``stepping.ensemble.run_batch``, which
steps many points in one call: ``batch_for``; a sweep worker on it starts without Numba)
compiled by Numba's ahead-of-time compiler (``numba.pycc``) for the argument types of the
built-in default run (the ``energy`` integrator, the Aiki–Kosugi laws; ``build`` takes
them from the default Config).  A run whose parameters have those types (``key``: their classes and
the Python types of their fields, whatever the values) calls the extension instead of the
JIT: its first step needs no compiling, and the process never imports Numba (its
kernels are made on first use, ``_jit.Kernel``).  Every other run uses the JIT as before.

Why not the JIT cache: it cannot be filled at install (its files are keyed by the source
files' paths and times, which an install changes), and loading from it is what costs the
second above.  Why ``numba.pycc``, which Numba has marked for deprecation: it is the only
ahead-of-time compiler of Numba code, and it compiles the same kernels with the same
options as the JIT (``_jit.JIT_OPTIONS``: fused multiply-adds, no reference counting),
for the host CPU as the JIT does, so both paths give the same bits
(tests/test_stepping_aot.py).  Its exported functions take arrays and scalars only, so a
run's five parameter tuples travel as one float64 row (``pack``, ``stepping.packing``) and
the generated wrappers (``wrapper_source``) rebuild them inside compiled code, and take the
run's arrays one by one and pass them on as the loop's one ``arrays.RunArrays``; the wrappers
release the GIL around the loop, as a JIT call does (``nogil``), so the process's other
threads keep running while it computes.

It is used only where its record (``_aot_loop.json``, beside it) matches the process:
the digest of the compiled sources (``_jit.SOURCES_DIGEST``: an edited checkout falls
back to the JIT), Numba's and llvmlite's versions, and the CPU, its model and feature flags (an
environment copied to another machine falls back too).  ``RODJIT_AOT=0`` turns it off.
An install that cannot build it (no C compiler, a failed compile) goes on without it.
"""
from __future__ import annotations

import hashlib
import importlib.metadata
import json
import os
import sys
from itertools import chain
from pathlib import Path

import numpy as np

from . import arrays as A
from . import packing as P
from .._jit import SOURCES_DIGEST
from .ensemble import run_batch
from .loop import advance, start

__all__ = ["EXTENSION", "AotLoop", "key", "pack", "wrapper_source", "build", "loop_for",
           "batch_for", "extension_record"]

EXTENSION = "_aot_loop"                  # the module rodjit.stepping._aot_loop
RECORD = EXTENSION + ".json"
_OFF = ("0", "false", "no", "off")

# the entry points: name, the loop function, the arguments after the parameter tuples
# (as the driver passes them: ``driver.run.Run``; the sweeps' batches: ``sweeps.ensemble``)
# with their types; each returns an int64.  ARRAYS stands for the run's arrays
# (``arrays.RunArrays``), which an exported function takes field by field (``_expand``)
# and its wrapper passes on as the NamedTuple
ARRAYS = "arrays"
_F3, _F2, _F1, _I2 = "f8[:,:,::1]", "f8[:,::1]", "f8[::1]", "i8[:,::1]"
ENTRIES = {
    "start": (start, (ARRAYS,)),
    "advance": (advance, (ARRAYS, ("max_steps", "i8"))),
    "run_batch": (run_batch, (("params", _F2), ("init", _F3), ("clock0", _F2),
                              ("flight", _F1), ("first", "i8"), ARRAYS, ("imp", _F1),
                              ("bout", _F2), ("fout", _F2), ("iout", _I2),
                              ("max_steps", "i8"))),
}


def _expand(args) -> list[tuple[str, str]]:
    """An entry's arguments (``ENTRIES``) with ARRAYS as the fields of ``RunArrays``."""
    out: list[tuple[str, str]] = []
    for a in args:
        out.extend([(f, A.aot_type(f)) for f in A.RunArrays._fields] if a == ARRAYS else [a])
    return out


def _flat(args) -> list:
    """Call arguments with a ``RunArrays`` as its fields: what an exported function takes."""
    out: list = []
    for a in args:
        if isinstance(a, A.RunArrays):
            out.extend(a)
        else:
            out.append(a)
    return out


def key(args) -> tuple:
    """What the compiled loop's signature depends on in the parameter tuples ``args``
    (scheme, control, system, rod law, floor law) beyond the fixed array types: each one's
    class and its fields' Python types (each field a scalar, whose type fixes its Numba
    type), as names, so that a record can hold it."""
    # the classes, then every field's type: unambiguous, a class fixing its field count
    types = (*map(type, args), *map(type, chain.from_iterable(args)))
    k = _KEYS.get(types)
    if k is None:
        k = _KEYS[types] = _Key((f"{type(p).__module__}.{type(p).__qualname__}",
                                 tuple(type(x).__name__ for x in p)) for p in args)
    return k


class _Key(tuple):
    """A ``key``: a tuple that computes its hash once.  The driver looks its compiled
    entries up by key at every run, and a key's two dozen strings made that hash a
    measurable part of a short run's set-up; equal to (and hashing as) the plain tuple."""

    def __init__(self, items):
        self._hash = tuple.__hash__(self)

    def __hash__(self):
        return self._hash


# ``key`` of each combination of types seen: the names once per process, since every
# compiled call of a run needs its key (a sweep of short rods makes thousands of runs)
_KEYS: dict[tuple, tuple] = {}


def pack(args) -> np.ndarray:
    """The fields of ``args`` as one float64 row (``packing.pack``, exact Python types
    only): what the wrappers of ``wrapper_source`` rebuild the tuples from."""
    return np.array(P.pack(args, exact=True), dtype=np.float64)


def wrapper_source(args) -> tuple[str, dict]:
    """Python source of the exported functions for parameter tuples of the types of
    ``args``, and the globals it needs: each rebuilds the tuples from the row ``p``
    (``pack``, ``packing.rebuild_source``), releases the GIL, calls the loop function and
    takes the GIL back."""
    glob = {f"_{name}": function for name, (function, _) in ENTRIES.items()}
    names = []
    for j, p in enumerate(args):
        names.append(f"_P{j}")
        glob[f"_P{j}"] = type(p)
    fields = P.rebuild_source(P.kinds(args, exact=True), "p", names)
    glob["_RunArrays"] = A.RunArrays
    run_arrays = f"_RunArrays({', '.join(A.RunArrays._fields)})"
    lines = []
    for name, (_, extra) in ENTRIES.items():
        arrays = ", ".join(a for a, _ in _expand(extra))
        passed = ", ".join(run_arrays if a == ARRAYS else a[0] for a in extra)
        lines += [f"def {name}(p, {arrays}):",
                  f"    a0, a1, a2, a3, a4 = {', '.join(fields)}",
                  "    ts = _save_thread()",
                  f"    code = _{name}(a0, a1, a2, a3, a4, {passed})",
                  "    _restore_thread(ts)",
                  "    return code", ""]
    return "\n".join(lines), glob


def _signature(name: str) -> str:
    return f"i8(f8[::1], {', '.join(t for _, t in _expand(ENTRIES[name][1]))})"


def _cpu() -> str:
    """The CPU the code is compiled for, told without loading LLVM where the system says
    it (Linux: the first processor of /proc/cpuinfo, its model and feature flags);
    elsewhere LLVM's host CPU name and features."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            first = []
            for line in f:
                if not line.strip():
                    break
                first.append(line)
    except OSError:
        first = []
    wanted = ("vendor_id", "cpu family", "model", "model name", "flags", "Features",
              "CPU implementer", "CPU architecture", "CPU variant", "CPU part")
    fields = {k.strip(): v.strip() for k, _, v in (ln.partition(":") for ln in first)}
    told = [f"{k}={fields[k]}" for k in wanted if k in fields]
    if told:
        return hashlib.sha1("\n".join(told).encode()).hexdigest()
    import llvmlite.binding as ll
    return f"{ll.get_host_cpu_name()} {ll.get_host_cpu_features().flatten()}"


def _version(dist: str) -> str | None:
    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return None


def _host() -> dict:
    """What the compiled code is tied to besides its sources (told without importing
    Numba, which a run on this loop never needs)."""
    return {"numba": _version("numba"), "llvmlite": _version("llvmlite"), "cpu": _cpu(),
            "python": f"{sys.implementation.cache_tag}"}


def build(directory: Path, args) -> Path:
    """Compile the extension for parameter tuples of the types of ``args`` into
    ``directory`` (its record beside it) and return its path.  Needs a C compiler."""
    from numba import types
    from numba.pycc import CC

    directory = Path(directory)
    source, glob = wrapper_source(args)
    glob["_save_thread"] = types.ExternalFunction("PyEval_SaveThread", types.voidptr())
    glob["_restore_thread"] = types.ExternalFunction("PyEval_RestoreThread",
                                                     types.void(types.voidptr))
    exec(compile(source, f"<rodjit.{EXTENSION} wrappers>", "exec"), glob)
    cc = CC(EXTENSION)
    cc.output_dir = str(directory)
    cc.target_cpu = "host"
    cc.verbose = False
    for name in ENTRIES:
        cc.export(name, _signature(name))(glob[name])
    record = directory / RECORD
    record.unlink(missing_ok=True)       # no record, no use: a failed build leaves none
    cc.compile()
    tmp = record.with_suffix(f".{os.getpid()}.tmp")
    tmp.write_text(json.dumps({"key": key(args), "sources": SOURCES_DIGEST, **_host()},
                              indent=1))
    os.replace(tmp, record)
    return directory / cc.output_file


def extension_record(directory: Path | None = None) -> dict | None:
    """The record of the built extension in ``directory`` (this module's by default), or
    None if there is none."""
    directory = Path(__file__).resolve().parent if directory is None else directory
    try:
        return json.loads((Path(directory) / RECORD).read_text())
    except (OSError, ValueError):
        return None


def reusable(directory: Path) -> Path | None:
    """The extension built in ``directory`` if it was built from these sources for this
    host (its record says so, ``_usable``) and is there: an install that finds one in
    the source tree keeps it instead of compiling the same loop again (an editable install
    with another extra, ``pip install -e ".[test]"`` after ``pip install -e .``)."""
    import sysconfig

    path = Path(directory) / (EXTENSION + str(sysconfig.get_config_var("EXT_SUFFIX")))
    return path if _usable(extension_record(directory)) and path.is_file() else None


def _usable(record: dict | None) -> bool:
    return (record is not None and record.get("sources") == SOURCES_DIGEST
            and all(record.get(k) == v for k, v in _host().items()))


_EXT: list = []      # [(module, key)] once looked up (module None: not usable)


def _extension():
    if not _EXT:
        module, k = None, None
        record = extension_record()
        if os.environ.get("RODJIT_AOT", "1").strip().lower() not in _OFF and _usable(record):
            try:
                from . import _aot_loop as module   # noqa: F811
            except ImportError:
                module = None
            k = tuple((c, tuple(t)) for c, t in record["key"])
        _EXT.append((module, k))
    return _EXT[0]


class AotLoop:
    """``start`` and ``advance`` of the extension for one run's parameter tuples: the
    driver's calls, with the tuples' fields packed once."""

    def __init__(self, module, args):
        self._start, self._advance = module.start, module.advance
        self.p = pack(args)

    def start(self, arrays):
        return self._start(self.p, *arrays)

    def advance(self, arrays, max_steps):
        return self._advance(self.p, *arrays, max_steps)


def _module_for(args, args_key: tuple | None):
    """The extension if it is usable and was built for the types of ``args`` (whose
    ``key`` the caller may already have), else None."""
    module, k = _extension()
    if module is None or (key(args) if args_key is None else args_key) != k:
        return None
    return module


def loop_for(args, args_key: tuple | None = None) -> AotLoop | None:
    """The ahead-of-time loop for parameter tuples ``args`` (whose ``key`` the caller may
    already have), or None (the JIT's turn): no usable extension, or one built for other
    types."""
    module = _module_for(args, args_key)
    return None if module is None else AotLoop(module, args)


def batch_for(args, args_key: tuple | None = None):
    """The ahead-of-time batch kernel (``stepping.ensemble.run_batch``) for points whose
    parameter tuples have the types of ``args`` (the batch's first point), as a function
    of the kernel's arguments after the tuples; or None (the JIT's turn), as ``loop_for``.
    A sweep's worker on it loads no JIT code: the half second of Numba's import and of
    loading the batch kernel from the JIT's cache, at each worker's start."""
    module = _module_for(args, args_key)
    if module is None:
        return None
    p = pack(args)
    entry = module.run_batch

    def call(*args):
        return entry(p, *_flat(args))

    return call
