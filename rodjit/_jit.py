"""The one set of Numba options every rodjit kernel is compiled with, and a cache guard.

``error_model="numpy"``: a division by zero gives inf/nan (which the admissibility checks
reject) instead of raising inside compiled code, and keeps loops vectorisable.
``fastmath={"contract"}``: LLVM may fuse a multiply and an add into one fused multiply-add
(one rounding instead of two, as ``gcc -O3`` does by default in the C speed limit,
benchmarks/limit.c).  No other fast-math flag: NaN, inf, signed zeros and the order of
operations keep their IEEE meaning, so the admissibility checks and the cancellation-free
forms of the laws stay as written.  Short rods' steps are chains of dependent multiply-adds,
which a fused instruction shortens (benchmarks/README.md has the measurements).  The price: on one machine a run still gives the same
bits every time, but they differ at rounding level from the plain-Python kernels'
(NUMBA_DISABLE_JIT=1) and from a CPU's without FMA, and a law's general path (no
``deriv_max``) gives the same run to rounding instead of bit for bit
(tests/test_kernels_fast_paths.py).
Fusing is more accurate per operation but not always overall: it can break a cancellation
of rounding errors that an algorithm relies on.  The pivots of Gaussian elimination,
p_i = d_i − e_(i−1)·(e_(i−1)/p_(i−1)), are one such case (a stiff, mass-scaled Newton
matrix: 3e-13 relative error unfused, 3e-9 fused; tests/test_kernels_banded_symmetric.py),
so the banded solvers are compiled unfused (``exact_kernel``, ``exact_step_kernel``).
Fast-math flags belong to each instruction, so they stay unfused when inlined into a fused
kernel; but a kernel that leaves ``fastmath`` unset is compiled with its caller's flags,
so these set it to False explicitly.
``cache=True``: compiled code is stored on disk, so later processes start warm.
``_nrt=False``: no reference counting.  Numba counts references to every array it holds:
each view (``state[0]``, ``work[R]``) and each array handed to a function costs calls to
NRT_incref/NRT_decref, which are never inlined, and every such call also makes the
floating-point values live across it spill from their registers.  The time loop makes
hundreds of them per step, a large share of a short rod's step (benchmarks/README.md).
rodjit's kernels never allocate and never keep an array beyond the call: they work
in arrays their caller owns for the whole call, so there is nothing to count.  Numba
refuses to compile an allocation, or the return of a new array, under this option, so
that guarantee is checked at compile time.
``nogil=True``: a compiled call releases the GIL, so the run file is written by another
thread while the loop computes (``driver.pipeline``); it changes only the Python entry
wrapper, not the compiled loop.
``no_cfunc_wrapper=True``: Numba would give every compiled kernel, beside the Python entry
wrapper, a C-ABI wrapper (for a kernel used as a first-class function value or a ctypes
address), which rodjit never uses; skipping it saves lowering, optimising and
code-generating one more function in every kernel's compile (the cold start of a run,
benchmarks/cold_start.py).
Stress laws written by users should use ``kernel`` too (and so must not allocate).

Literal flags: a ``True``/``False`` written in a kernel is a compile-time literal to Numba,
and a kernel called with a literal is compiled for that value.  A flag passed as ``True``
at one call site and as ``False`` or a run-time bool at another, or a variable that starts
as a literal and later takes run-time values (type inference compiles the callee for the
literal first), so compiles the callee twice, and each copy is optimised and
code-generated again in every caller it is inlined into.  Kernels pass such flags as
``bool(True)``/``bool(False)``, a run-time bool: one compile serves every call site, and a
caller that passes a constant folds the flag's branches once the callee is inlined.  A
branch on a flag must not merely rescale a value that the code after it uses (``if
flag: x *= c``, then ``y += x``): LLVM turns that into ``x * select(flag, c, 1)`` and the
fused multiply-add of the literal compile is lost; each branch does its own update
(``forces.add_beam_term``).  A literal stays where a compile per value pays at run time:
the energy step's residual evaluation with and without the Jacobian (``energy._evaluate``)
are two different passes, and one compile of both behind a run-time flag, inlined twice,
makes the step several per cent slower.  tests/test_cache.py checks that a run compiles
every other kernel once.

Numba invalidates a cached function only when *its own* file changes, not when a function
it calls does (a law, an event helper): ``_guard_cache`` drops rodjit's cache files whenever
any source of the compiled layers differs from the last process that compiled them.
"""
from __future__ import annotations

import errno
import hashlib
import os
from pathlib import Path

import numba
from numba.core import caching
from numba.core.cpu import CPUTargetOptions

# ``_nrt`` is an option of Numba's CPU target (Numba compiles its own allocation-free
# helpers with it); a Numba without it compiles the kernels with reference counting
_CAN_DISABLE_NRT = hasattr(CPUTargetOptions, "_nrt")
_CAN_SKIP_CFUNC = hasattr(CPUTargetOptions, "no_cfunc_wrapper")
JIT_OPTIONS = {"cache": True, "error_model": "numpy", "nogil": True,
               "fastmath": {"contract"}, **({"_nrt": False} if _CAN_DISABLE_NRT else {}),
               **({"no_cfunc_wrapper": True} if _CAN_SKIP_CFUNC else {})}

_kernel = numba.njit(**JIT_OPTIONS)


def kernel(func):
    """Compile ``func`` as a rodjit kernel (``rodjit.laws.law_kernel``).

    The options every rodjit kernel has (``JIT_OPTIONS``): cached on disk, NumPy's error
    model, the GIL released, fused multiply-adds and, where Numba allows, no reference
    counting, so a kernel must not allocate.

    Parameters
    ----------
    func : function
        A Python function Numba can compile in nopython mode.

    Returns
    -------
    numba.core.registry.CPUDispatcher
        The compiled function, callable from Python and from other kernels.
    """
    return _kernel(func)


def python_function(compiled):
    """The Python function a kernel was compiled from (itself where Numba is off).

    For a few scalars evaluated from Python (a law's value at one point, a record of a
    dozen copies): a compiled call's dispatch costs more than that arithmetic, and the
    first compiled call of a process loads Numba's typing and target machinery (about a
    second), which a run of the ahead-of-time loop (``stepping.aot``) never needs.  The
    Python function computes the same IEEE operations, but without the fused multiply-adds
    the kernel may use, so a value can differ from the kernel's in its last bit."""
    return getattr(compiled, "py_func", compiled)


# no fused multiply-adds (module docstring): the banded solvers' elimination recurrences
exact_kernel = numba.njit(**{**JIT_OPTIONS, "fastmath": False})

# Kernels called on every step of the time loop (the step, its forces and sub-steps, the
# event and step-size helpers, the stress laws) are also marked for inlining into the loop
# (LLVM alwaysinline), and so are the overloads that dispatch to them (``STEP_JIT_OPTIONS``:
# the scheme's step, the law functions): a step then makes no calls and passes no arrays,
# which matters for short rods, where the work per step is a few dozen flops and the calls
# would cost more than the arithmetic (benchmarks/bench_scipy.py).  A call also makes every live
# floating-point register spill (all are caller-saved).  Numba without the option compiles
# them as plain kernels.
_CAN_FORCE_INLINE = hasattr(CPUTargetOptions, "forceinline")
STEP_JIT_OPTIONS = {**JIT_OPTIONS, **({"forceinline": True} if _CAN_FORCE_INLINE else {})}
step_kernel = numba.njit(**STEP_JIT_OPTIONS)
exact_step_kernel = numba.njit(**{**STEP_JIT_OPTIONS, "fastmath": False})

# the packages whose modules hold compiled code (a change anywhere here may change a kernel)
COMPILED_PACKAGES = ("model/laws", "kernels", "stepping")


def _source_dirs(root: Path) -> list[Path]:
    return sorted({p.parent for p in root.rglob("*.py")})


def _cache_dirs(root: Path) -> list[Path]:
    """Where Numba keeps rodjit's cache files: next to the sources, or in NUMBA_CACHE_DIR
    one directory per source directory, named by Numba as ``<name>_<sha1 of its path>``."""
    dirs = [p for p in root.rglob("__pycache__") if p.is_dir()]
    if numba.config.CACHE_DIR:
        for d in _source_dirs(root):
            sub = caching._CacheLocator.get_suitable_cache_subpath(str(d / "__init__.py"))
            p = Path(numba.config.CACHE_DIR) / sub
            if p.is_dir():
                dirs.append(p)
    return dirs


def _sources_digest(root: Path) -> str:
    """SHA-1 of Numba's version and of every module that holds compiled code (its path and
    bytes): what compiled machine code was made from."""
    digest = hashlib.sha1(numba.__version__.encode())
    compiled = [root / "_jit.py"] + [p for d in COMPILED_PACKAGES for p in (root / d).rglob("*.py")]
    for p in sorted(compiled):
        digest.update(p.relative_to(root).as_posix().encode())
        digest.update(p.read_bytes())
    return digest.hexdigest()


# of this install's sources: the disk cache below and the ahead-of-time loop
# (``stepping.aot``) are used only for code made from these
SOURCES_DIGEST = _sources_digest(Path(__file__).resolve().parent)


def _guard_cache() -> None:
    root = Path(__file__).resolve().parent
    stamp_dir = (Path(numba.config.CACHE_DIR) / root.relative_to(root.anchor)
                 if numba.config.CACHE_DIR else root / "__pycache__")
    stamp = stamp_dir / "rodjit-sources.sha1"
    try:
        if stamp.read_text() == SOURCES_DIGEST:
            return
    except OSError:
        pass
    for d in _cache_dirs(root):
        for f in list(d.rglob("*.nbi")) + list(d.rglob("*.nbc")):
            try:
                f.unlink()
            except OSError:
                pass
    try:
        stamp_dir.mkdir(parents=True, exist_ok=True)
        tmp = stamp.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(SOURCES_DIGEST)
        os.replace(tmp, stamp)
    except OSError:
        pass  # read-only install: Numba falls back to its user-wide cache


_guard_cache()

# What a disk says when it refuses a cache file: full, a file-size limit or quota, read-only,
# not ours, an I/O error.
_CACHE_REFUSALS = frozenset({errno.ENOSPC, errno.EFBIG, errno.EDQUOT, errno.EROFS,
                             errno.EACCES, errno.EPERM, errno.EIO})


def _tolerate_refused_cache_writes() -> None:
    """A kernel whose machine code cannot be written to Numba's disk cache still runs.

    Numba saves a compiled kernel inside the call that compiled it and lets an OSError of
    that save escape, so a full disk or a file-size limit (``ulimit -f``) on the cache
    directory would fail a run or a sweep point that has its machine code in hand.  The
    save is skipped instead, silently (a line on stderr would break the one-line report of
    the command that hit the full disk); the only cost is compiling again in the next
    process.  Other errors of the save are Numba's to report."""
    original = caching.Cache.save_overload
    if getattr(original, "rodjit_tolerant", False):
        return

    def save_overload(self, sig, data):
        try:
            original(self, sig, data)
        except OSError as exc:
            if exc.errno not in _CACHE_REFUSALS:
                raise

    save_overload.rodjit_tolerant = True
    save_overload.__doc__ = original.__doc__
    caching.Cache.save_overload = save_overload


_tolerate_refused_cache_writes()
