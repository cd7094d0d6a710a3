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
``nogil=True``: a compiled call releases the GIL, so the process's other Python threads
keep running while the loop computes (a sweep worker's watch on its parent,
``sweeps.pool``); it changes only the Python entry wrapper, not the compiled loop.
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

Numba is imported only where something is compiled: a kernel is a ``Kernel``, which makes
its Numba dispatcher on first use, and the overloads and intrinsics of the compiled layers
are registered with Numba when it loads (``overload``, ``when_loaded``, ``load_numba``).  A
process that calls no kernel (a run on the loop compiled ahead of time, ``stepping.aot``;
reading a run file; ``rodjit --help``) never imports Numba, which is a third of such a
process's start-up.

Numba invalidates a cached function only when *its own* file changes, not when a function
it calls does (a law, an event helper): ``_guard_cache`` drops rodjit's cache files whenever
any source of the compiled layers differs from the last process that compiled them.
"""
from __future__ import annotations

import errno
import functools
import hashlib
import importlib
import importlib.abc
import importlib.util
import os
import sys
import threading
import types
from pathlib import Path
from typing import Any, Callable, cast

# Filled in by ``load_numba`` from what the installed Numba's CPU target offers (module
# docstring); read them through this module (``_jit.JIT_OPTIONS``) once Numba is loaded.
JIT_OPTIONS: dict = {}
STEP_JIT_OPTIONS: dict = {}
_CAN_DISABLE_NRT = _CAN_SKIP_CFUNC = _CAN_FORCE_INLINE = False


def _options(numba_core_cpu) -> None:
    """Set the option sets of the four kinds of kernel for this Numba."""
    global _CAN_DISABLE_NRT, _CAN_SKIP_CFUNC, _CAN_FORCE_INLINE
    target = numba_core_cpu.CPUTargetOptions
    # ``_nrt`` is an option of Numba's CPU target (Numba compiles its own allocation-free
    # helpers with it); a Numba without it compiles the kernels with reference counting
    _CAN_DISABLE_NRT = hasattr(target, "_nrt")
    _CAN_SKIP_CFUNC = hasattr(target, "no_cfunc_wrapper")
    # Kernels called on every step of the time loop (the step, its forces and sub-steps,
    # the event and step-size helpers, the stress laws) are also marked for inlining into
    # the loop (LLVM alwaysinline), and so are the overloads that dispatch to them (the
    # scheme's step, the law functions): a step then makes no calls and passes no arrays,
    # which matters for short rods, where the work per step is a few dozen flops and the
    # calls would cost more than the arithmetic (benchmarks/bench_scipy.py).  A call also
    # makes every live floating-point register spill (all are caller-saved).  Numba
    # without the option compiles them as plain kernels.
    _CAN_FORCE_INLINE = hasattr(target, "forceinline")
    JIT_OPTIONS.update({"cache": True, "error_model": "numpy", "nogil": True,
                        "fastmath": {"contract"},
                        **({"_nrt": False} if _CAN_DISABLE_NRT else {}),
                        **({"no_cfunc_wrapper": True} if _CAN_SKIP_CFUNC else {})})
    STEP_JIT_OPTIONS.update({**JIT_OPTIONS,
                             **({"forceinline": True} if _CAN_FORCE_INLINE else {})})
    # no fused multiply-adds (module docstring): the banded solvers' recurrences
    _KIND_OPTIONS.update({"plain": JIT_OPTIONS, "step": STEP_JIT_OPTIONS,
                          "exact": {**JIT_OPTIONS, "fastmath": False},
                          "exact_step": {**STEP_JIT_OPTIONS, "fastmath": False}})


_KIND_OPTIONS: dict[str, dict] = {}
# every function given an ``overload`` -> its typing implementation (``overload``)
OVERLOADS: dict[Callable, Callable] = {}
_LOCK = threading.RLock()
_WHEN_LOADED: list[Callable[[], None]] = []
_STATE = {"loaded": False, "loading": False}


def check_numba_environment() -> None:
    """ValueError (one line naming the variable) if ``NUMBA_NUM_THREADS`` is set to what
    Numba cannot use: Numba's import fails on 0 with "Number of threads specified must be
    > 0." and answers a non-number with a warning holding its own traceback, neither
    naming the variable; a run would fail (or warn) only once it compiles, after its file
    was made.  The command line checks it before any verb runs (``rodjit.entry``)."""
    text = os.environ.get("NUMBA_NUM_THREADS")
    if text is None:
        return
    try:
        threads = int(text)
    except ValueError:
        threads = 0
    if threads < 1:
        raise ValueError(f"environment variable NUMBA_NUM_THREADS = {text[:40]!r} is out of "
                         f"range (a whole number of threads >= 1, or unset)")


def load_numba():
    """Import Numba and make ready what rodjit compiles with it, once per process; return
    the ``numba`` module.

    Ready means: the option sets read from this Numba, the disk-cache guards installed
    (``_guard_cache``, ``_tolerate_refused_cache_writes``), and every registration that
    waits for Numba (``when_loaded``: the overloads and intrinsics of the compiled layers)
    made.  It runs when a kernel is first compiled or inspected, and when anything in the
    process imports Numba (``_AfterNumba``), so Numba code of a user's own that calls
    rodjit's generic functions (``rodjit.laws.value``) finds them registered."""
    if _STATE["loaded"]:
        return sys.modules["numba"]
    with _LOCK:
        if not (_STATE["loaded"] or _STATE["loading"]):
            _STATE["loading"] = True
            try:
                check_numba_environment()
                import numba
                import numba.core.cpu

                _options(numba.core.cpu)
                _guard_cache()
                _tolerate_refused_cache_writes()
                while _WHEN_LOADED:
                    _WHEN_LOADED.pop(0)()
                _STATE["loaded"] = True
            finally:
                _STATE["loading"] = False
    return sys.modules["numba"]


def when_loaded(register: Callable[[], None]) -> None:
    """Call ``register`` once Numba is loaded (now, if it is): for what a module must tell
    Numba before anything is compiled (an overload, an intrinsic) but that would otherwise
    import Numba with the module."""
    with _LOCK:
        if _STATE["loaded"]:
            register()
        else:
            _WHEN_LOADED.append(register)


def overload(func, *, kind: str = "step", python_wrapper: bool = False, **kwargs):
    """``numba.extending.overload(func, ...)``, registered when Numba loads: the decorated
    implementation is compiled with the options of ``kind`` (``"step"``: inlined into the
    loop, as the kernels it dispatches to; ``"plain"``), plus Numba's Python entry wrapper
    if ``python_wrapper`` (which overloads leave out by default).  Other keywords go to
    Numba's ``overload``.  Returns the implementation unchanged.

    The implementation is also kept in ``OVERLOADS`` (``func`` -> ``impl``), so the same
    compile-time dispatch can be registered for another Numba target (``rodjit.gpu``)."""
    def decorate(impl):
        OVERLOADS[func] = impl
        def register():
            from numba.extending import overload as numba_overload

            options = dict(_KIND_OPTIONS[kind])
            if python_wrapper:
                options["no_cpython_wrapper"] = False
            numba_overload(func, jit_options=options, **kwargs)(impl)

        when_loaded(register)
        return impl

    return decorate


class Kernel:
    """A rodjit kernel: a Python function and the kind of Numba options it compiles with,
    turned into Numba's dispatcher (``numba.njit``) the first time it is called, compiled
    into another kernel or asked for a dispatcher's attribute (``signatures``, ``stats``).

    Why not ``numba.njit`` at import: importing Numba takes a third of a second, and a run
    on the loop compiled ahead of time (``stepping.aot``) calls no kernel; with the
    dispatchers made on demand, such a run never imports Numba.  Compiled code sees the
    dispatcher itself: Numba types a kernel by its ``_numba_type_``, so a kernel called
    from another compiles, inlines and caches as a dispatcher would."""

    def __init__(self, func, kind: str):
        functools.update_wrapper(self, func)
        self.py_func = func
        self._kind = kind
        self._dispatcher = None

    @property
    def dispatcher(self):
        """Numba's dispatcher of this kernel (made, and Numba loaded, on first use)."""
        if self._dispatcher is None:
            numba = load_numba()
            with _LOCK:
                if self._dispatcher is None:
                    self._dispatcher = numba.njit(**_KIND_OPTIONS[self._kind])(self.py_func)
        return self._dispatcher

    @property
    def _numba_type_(self):
        from numba.core import types

        return types.Dispatcher(self.dispatcher)

    def __call__(self, *args):
        return self.dispatcher(*args)

    def entry_point(self, args):
        """The compiled function for the types of ``args``, compiled (or loaded from the
        disk cache) if it is not yet: Numba's C entry, which unboxes the arguments and
        runs the machine code, releasing the GIL as the dispatcher's call does.

        Why: the dispatcher types every argument of every call, about 5 µs for the time
        loop's arguments (six parameter tuples and a tuple of 16 arrays), which a short
        rod's whole run of a few hundred steps pays twice; the entry costs under 1 µs.  It does not check
        its arguments, so a caller must pass only arguments of exactly these types (the
        driver keeps one per ``stepping.aot.key`` of a run, whose arrays it allocates
        itself).  Where Numba is off, the Python function."""
        dispatcher = self.dispatcher
        if not hasattr(dispatcher, "overloads"):       # NUMBA_DISABLE_JIT=1
            return dispatcher
        from numba.core.typing.typeof import Purpose, typeof

        return dispatcher.compile(tuple(typeof(a, Purpose.argument) for a in args))

    def __getattr__(self, name):
        # only names this object lacks reach here; dunder lookups (pickle, copy) must not
        # load Numba
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(self.dispatcher, name)

    def __reduce__(self):
        return _kernel_named, (self.__module__, self.__qualname__)

    def __repr__(self):
        return f"<rodjit kernel {self.__module__}.{self.__qualname__}>"


def _kernel_named(module: str, qualname: str) -> Kernel:
    obj: Any = importlib.import_module(module)
    for part in qualname.split("."):
        obj = getattr(obj, part)
    return cast(Kernel, obj)


def kernel(func) -> Kernel:
    """Compile ``func`` as a rodjit kernel (``rodjit.laws.law_kernel``).

    The options every rodjit kernel has (``JIT_OPTIONS``): cached on disk, NumPy's error
    model, the GIL released, fused multiply-adds and, where Numba allows, no reference
    counting, so a kernel must not allocate.  Compiled on first use (``Kernel``).

    Parameters
    ----------
    func : function
        A Python function Numba can compile in nopython mode.

    Returns
    -------
    Kernel
        The kernel, callable from Python and from other kernels and from any Numba code.
    """
    return Kernel(func, "plain")


def step_kernel(func) -> Kernel:
    """A kernel called on every step, inlined into the loop (``STEP_JIT_OPTIONS``)."""
    return Kernel(func, "step")


def exact_kernel(func) -> Kernel:
    """A kernel compiled without fused multiply-adds (module docstring)."""
    return Kernel(func, "exact")


def exact_step_kernel(func) -> Kernel:
    """A step kernel compiled without fused multiply-adds."""
    return Kernel(func, "exact_step")


def python_function(compiled):
    """The Python function a kernel was compiled from (itself where Numba is off).

    For a few scalars evaluated from Python (a law's value at one point, a record of a
    dozen copies): a compiled call's dispatch costs more than that arithmetic, and the
    first compiled call of a process loads Numba (about a second, with its typing and
    target machinery), which a run of the ahead-of-time loop (``stepping.aot``) never
    needs.  The Python function computes the same IEEE operations, but without the fused
    multiply-adds the kernel may use, so a value can differ from the kernel's in its last
    bit."""
    return getattr(compiled, "py_func", compiled)


def numba_loaded() -> bool:
    """Whether this process has loaded Numba (``load_numba``): a kernel called now costs
    its dispatch only, not Numba's import."""
    return _STATE["loaded"]


def python_module(module) -> types.SimpleNamespace:
    """The names of ``module`` with each of its kernels replaced by its Python function,
    whose calls to the module's other kernels go to their Python functions too: the
    module's code run by the interpreter, without Numba (``python_function`` for one
    kernel).  Its values are the compiled ones to the bit where every kernel is compiled
    without fused multiply-adds (``exact_kernel``) and calls no kernel of another module."""
    names = dict(vars(module))
    for name, obj in vars(module).items():
        if isinstance(obj, Kernel):
            f = obj.py_func
            names[name] = types.FunctionType(f.__code__, names, f.__name__, f.__defaults__,
                                             f.__closure__)
    return types.SimpleNamespace(**names)


class _AfterNumba(importlib.abc.MetaPathFinder):
    """Makes ``load_numba`` follow the import of Numba by anyone in the process: rodjit's
    overloads must be registered before Numba types code that calls them, whoever
    compiles it."""

    def find_spec(self, name, path=None, target=None):
        if name != "numba":
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return spec
        exec_numba = spec.loader.exec_module

        def exec_module(module):
            exec_numba(module)
            load_numba()

        spec.loader.exec_module = exec_module
        return spec


# the packages whose modules hold compiled code (a change anywhere here may change a kernel)
COMPILED_PACKAGES = ("model/laws", "kernels", "stepping")


def _source_dirs(root: Path) -> list[Path]:
    return sorted({p.parent for p in root.rglob("*.py")})


def _cache_dirs(root: Path) -> list[Path]:
    """Where Numba keeps rodjit's cache files: next to the sources, or in NUMBA_CACHE_DIR
    one directory per source directory, named by Numba as ``<name>_<sha1 of its path>``."""
    from numba.core import caching

    dirs = [p for p in root.rglob("__pycache__") if p.is_dir()]
    cache_dir = _numba_cache_dir()
    if cache_dir:
        for d in _source_dirs(root):
            sub = caching._CacheLocator.get_suitable_cache_subpath(str(d / "__init__.py"))
            p = Path(cache_dir) / sub
            if p.is_dir():
                dirs.append(p)
    return dirs


def _numba_cache_dir() -> str:
    """``NUMBA_CACHE_DIR`` as Numba read it ("" when unset); ``numba.config`` sets its
    attributes from the environment at run time, so a type checker cannot see them."""
    import numba

    return str(getattr(numba.config, "CACHE_DIR", "") or "")


def _sources_digest(root: Path) -> str:
    """SHA-1 of every module that holds compiled code (its path and bytes): what compiled
    machine code was made from, besides the compiler (Numba's version is checked apart:
    ``_guard_cache``, ``stepping.aot``)."""
    digest = hashlib.sha1()
    compiled = [root / "_jit.py"] + [p for d in COMPILED_PACKAGES for p in (root / d).rglob("*.py")]
    for p in sorted(compiled):
        digest.update(p.relative_to(root).as_posix().encode())
        digest.update(p.read_bytes())
    return digest.hexdigest()


# of this install's sources: the disk cache below and the ahead-of-time loop
# (``stepping.aot``) are used only for code made from these
SOURCES_DIGEST = _sources_digest(Path(__file__).resolve().parent)


def _guard_cache() -> None:
    """Drop rodjit's cache files if the compiled sources or Numba changed since the last
    process that compiled them (module docstring)."""
    import numba

    root = Path(__file__).resolve().parent
    made_from = f"{SOURCES_DIGEST} numba {numba.__version__}"
    cache_dir = _numba_cache_dir()
    stamp_dir = (Path(cache_dir) / root.relative_to(root.anchor)
                 if cache_dir else root / "__pycache__")
    stamp = stamp_dir / "rodjit-sources.sha1"
    try:
        if stamp.read_text() == made_from:
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
        tmp.write_text(made_from)
        os.replace(tmp, stamp)
    except OSError:
        pass  # read-only install: Numba falls back to its user-wide cache


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
    process.  Other errors of the save are Numba's to report.

    Why a replaced method and not a supported mechanism: Numba (0.58 to 0.68) documents
    only ``cache=True`` and ``NUMBA_CACHE_DIR``; everything else about its cache lives in
    ``numba.core.caching``, which it does not document.  Its one registry,
    ``_CacheImpl._locator_classes``, chooses *where* the files go and is asked before the
    compile (``ensure_cache_path`` proves the directory writable with an empty file), not
    when the write itself fails; a full disk or ``ulimit -f`` refuse the write, not the
    directory.  A ``FunctionCache`` subclass per dispatcher would need the private
    ``Dispatcher._cache`` and would not reach the overloads compiled with ``jit_options``
    (``overload``), which Numba caches too.  So the smallest dependency is this one method:
    ``Cache.save_overload(self, sig, data)``, inherited unchanged by ``FunctionCache``.
    tests/test_jit_cache_guard.py fails when Numba changes its name, its signature, who
    inherits it, or that it is what a compile calls to write the cache."""
    from numba.core import caching

    original = caching.Cache.save_overload
    if getattr(original, "rodjit_tolerant", False):
        return

    @functools.wraps(original)        # keeps its name, doc and signature (``__wrapped__``)
    def save_overload(self, sig, data):
        try:
            original(self, sig, data)
        except OSError as exc:
            if exc.errno not in _CACHE_REFUSALS:
                raise

    save_overload.rodjit_tolerant = True     # type: ignore[attr-defined]
    caching.Cache.save_overload = save_overload    # type: ignore[method-assign]


# Numba already imported (by the user, before rodjit): ready it now; otherwise when it is
if "numba" in sys.modules:
    load_numba()
else:
    sys.meta_path.insert(0, _AfterNumba())
