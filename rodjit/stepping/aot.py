"""The compiled loops of the integrators the default run chooses from, and the sweeps'
batch kernel for the same types, compiled ahead of time at install.

Numba compiles ``loop.start`` and ``loop.advance`` the first time a process calls them:
20–40 s for ``dop853`` or ``radau5`` on a fresh install, and a later process, which loads
them from Numba's disk cache, still pays Numba's own start-up (its import, typing and
target machinery, about a second here) before its first step.  So ``pip install`` builds,
where it can, an extension module ``rodjit.stepping._aot_loop``: the two functions and the
batch kernel of the sweeps' ensemble engine (``stepping.ensemble.run_batch``, which steps
many points in one call: ``batch_for``; a sweep worker on it starts without Numba)
compiled by Numba's ahead-of-time compiler (``numba.pycc``), once per integrator that
``time.integrator = "auto"`` chooses (``dop853`` at μ = 0, ``radau5`` at μ > 0: the
registry's ``Scheme.aot`` rows, ``schemes``), for the argument types of the built-in
default run with that integrator (the Aiki–Kosugi laws, its control and system; ``build``
takes them from the default Config).  Each integrator's functions carry its name
(``advance_dop853``, ``tag``).  A run whose parameters have the types of one of them
(``key``: their classes and the Python types of their fields, whatever the values) calls
the extension instead of the JIT: its first step needs no compiling, and the process never
imports Numba (its kernels are made on first use, ``_jit.Kernel``).  Every other run uses
the JIT as before; ``energy``, ``verlet`` and the rest compile on first use.

Which integrators, measured by calling ``build`` as setup.py does (a fresh interpreter and
Numba cache, 2 cores shared with other work, load average 2–5): ``energy`` alone (the
build before ``auto``) 37 s of wall time (34 s of CPU); ``dop853`` and ``radau5`` in one
module 73–107 s (66–70 s of CPU); ``energy`` with them 151 s (88 s of CPU), so ``energy``
is left to the JIT, which compiles it in its first run (24–33 s).  One module rather than
one per integrator built in two processes at once: the two took 179 s of wall (87 s of
CPU: the laws, forces and loop helpers the integrators share are compiled once in one
module, twice in two), and two cores shared with other work did not run them side by
side.

Why not the JIT cache: it cannot be filled at install (its files are keyed by the source
files' paths and times, which an install changes), and loading from it is what costs the
second above.  Why ``numba.pycc``, which Numba has marked for deprecation: it is the only
ahead-of-time compiler of Numba code, and it compiles the same kernels with the same
options as the JIT (``_jit.JIT_OPTIONS``: fused multiply-adds, no reference counting),
for the host CPU as the JIT does, so both paths give the same bits
(tests/test_stepping_aot.py).  Its exported functions take arrays and scalars only, so a
run's six parameter tuples travel as one float64 row (``pack``, ``stepping.packing``) and
the generated wrappers (``wrapper_source``) rebuild them inside compiled code, and take the
run's arrays one by one and pass them on as the loop's one ``arrays.RunArrays``; the wrappers
release the GIL around the loop, as a JIT call does (``nogil``), so the process's other
threads keep running while it computes.

It is used only where its record (``_aot_loop.json``, beside it: each integrator's suffix
and ``key``) matches the process: the digest of the compiled sources
(``_jit.SOURCES_DIGEST``: an edited checkout falls back to the JIT), Numba's and
llvmlite's versions, and the CPU, its model and feature flags (an environment copied to
another machine falls back too).  ``RODJIT_AOT=0`` turns it off.  An install that cannot
build it (no C compiler, a failed compile) goes on without it.
"""
from __future__ import annotations

import hashlib
import importlib.metadata
import json
import os
import re
import sys
from itertools import chain
from pathlib import Path

import numpy as np

from . import arrays as A
from . import packing as P
from . import registry
from .._jit import SOURCES_DIGEST
from .ensemble import run_batch
from .loop import advance, start

__all__ = ["EXTENSION", "AotLoop", "schemes", "tag", "key", "pack", "wrapper_source", "build",
           "loop_for", "batch_for", "extension_record"]

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


def schemes() -> tuple[str, ...]:
    """The integrators the install compiles ahead of time: the registry's ``Scheme.aot``
    rows (the ones ``time.integrator = "auto"`` chooses from)."""
    return tuple(s.name for s in registry.SCHEMES if s.aot)


def tag(args) -> str:
    """The suffix of the exported functions for parameter tuples ``args``
    (``advance_dop853``): the name of their scheme, as an identifier."""
    return re.sub(r"\W", "_", registry.entry_of(type(args[0])).name)


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
    (scheme, control, system, rod law, floor law, observer) beyond the fixed array types:
    each one's class and its fields' Python types (each field a scalar, whose type fixes its
    Numba type), as names, so that a record can hold it."""
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


def wrapper_source(args, suffix: str) -> tuple[str, dict]:
    """Python source of the exported functions for parameter tuples of the types of
    ``args`` (each entry's name with ``_suffix``: ``advance_dop853``), and the globals it
    needs: each rebuilds the tuples from the row ``p`` (``pack``,
    ``packing.rebuild_source``), releases the GIL, calls the loop function and takes the GIL
    back."""
    glob = {f"_{name}": function for name, (function, _) in ENTRIES.items()}
    names = []
    for j, p in enumerate(args):
        names.append(f"_P{j}")
        glob[f"_P{j}"] = type(p)
    fields = P.rebuild_source(P.kinds(args, exact=True), "p", names)
    tuples = ", ".join(f"a{j}" for j in range(len(args)))
    glob["_RunArrays"] = A.RunArrays
    run_arrays = f"_RunArrays({', '.join(A.RunArrays._fields)})"
    lines = []
    for name, (_, extra) in ENTRIES.items():
        arrays = ", ".join(a for a, _ in _expand(extra))
        passed = ", ".join(run_arrays if a == ARRAYS else a[0] for a in extra)
        lines += [f"def {name}_{suffix}(p, {arrays}):",
                  f"    {tuples} = {', '.join(fields)}",
                  "    ts = _save_thread()",
                  f"    code = _{name}({tuples}, {passed})",
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


def build(directory: Path, runs) -> Path:
    """Compile the extension for each of ``runs`` (parameter tuples, one set per scheme:
    the entries for their types, suffixed with their ``tag``) into ``directory`` (its
    record beside it) and return its path.  Needs a C compiler."""
    from numba import types
    from numba.pycc import CC

    directory = Path(directory)
    cc = CC(EXTENSION)
    cc.output_dir = str(directory)
    cc.target_cpu = "host"
    cc.verbose = False
    entries = []
    gil = {"_save_thread": types.ExternalFunction("PyEval_SaveThread", types.voidptr()),
           "_restore_thread": types.ExternalFunction("PyEval_RestoreThread",
                                                     types.void(types.voidptr))}
    for args in runs:
        suffix = tag(args)
        source, glob = wrapper_source(args, suffix)
        glob.update(gil)
        exec(compile(source, f"<rodjit.{EXTENSION} wrappers, {suffix}>", "exec"), glob)
        for name in ENTRIES:
            cc.export(f"{name}_{suffix}", _signature(name))(glob[f"{name}_{suffix}"])
        entries.append([suffix, key(args)])
    record = directory / RECORD
    record.unlink(missing_ok=True)       # no record, no use: a failed build leaves none
    cc.compile()
    tmp = record.with_suffix(f".{os.getpid()}.tmp")
    tmp.write_text(json.dumps({"entries": entries, "sources": SOURCES_DIGEST, **_host()},
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
    return (record is not None and isinstance(record.get("entries"), list)
            and record.get("sources") == SOURCES_DIGEST
            and all(record.get(k) == v for k, v in _host().items()))


# [(module, {key: tag})] once looked up: the extension and the suffix of its entries for
# each key it was built for (module None, no keys: not usable)
_EXT: list = []


def _extension():
    if not _EXT:
        module, tags = None, {}
        record = extension_record()
        if os.environ.get("RODJIT_AOT", "1").strip().lower() not in _OFF and _usable(record):
            try:
                from . import _aot_loop as module   # noqa: F811
            except ImportError:
                module = None
            else:
                tags = {tuple((c, tuple(t)) for c, t in k): suffix
                        for suffix, k in record["entries"]}
        _EXT.append((module, tags))
    return _EXT[0]


class AotLoop:
    """``start`` and ``advance`` of the extension for one run's parameter tuples (the
    entries with the suffix ``suffix``): the driver's calls, with the tuples' fields packed
    once."""

    def __init__(self, module, suffix: str, args):
        self._start = getattr(module, f"start_{suffix}")
        self._advance = getattr(module, f"advance_{suffix}")
        self.p = pack(args)

    def start(self, arrays):
        return self._start(self.p, *arrays)

    def advance(self, arrays, max_steps):
        return self._advance(self.p, *arrays, max_steps)


def _entries_for(args, args_key: tuple | None):
    """``(extension, suffix)`` of the entries built for the types of ``args`` (whose
    ``key`` the caller may already have) if the extension is usable and has them, else
    None."""
    module, tags = _extension()
    if module is None:
        return None
    suffix = tags.get(key(args) if args_key is None else args_key)
    return None if suffix is None else (module, suffix)


def loop_for(args, args_key: tuple | None = None) -> AotLoop | None:
    """The ahead-of-time loop for parameter tuples ``args`` (whose ``key`` the caller may
    already have), or None (the JIT's turn): no usable extension, or none of its entries
    built for these types."""
    found = _entries_for(args, args_key)
    return None if found is None else AotLoop(*found, args)


def batch_for(args, args_key: tuple | None = None):
    """The ahead-of-time batch kernel (``stepping.ensemble.run_batch``) for points whose
    parameter tuples have the types of ``args`` (the batch's first point), as a function
    of the kernel's arguments after the tuples; or None (the JIT's turn), as ``loop_for``.
    A sweep's worker on it loads no JIT code: the half second of Numba's import and of
    loading the batch kernel from the JIT's cache, at each worker's start."""
    found = _entries_for(args, args_key)
    if found is None:
        return None
    module, suffix = found
    p = pack(args)
    entry = getattr(module, f"run_batch_{suffix}")

    def call(*args):
        return entry(p, *_flat(args))

    return call
