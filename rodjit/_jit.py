"""The one set of Numba options every rodjit kernel is compiled with, and a cache guard.

``error_model="numpy"``: a division by zero gives inf/nan (which the admissibility checks
reject) instead of raising inside compiled code, and keeps loops vectorisable.
``cache=True``: compiled code is stored on disk, so later processes start warm.
``nogil=True``: a compiled call releases the GIL, so the run file is written by another
thread while the loop computes (``driver.pipeline``); it changes only the Python entry
wrapper, not the compiled loop.
Stress laws written by users should use ``kernel`` too.

Numba invalidates a cached function only when *its own* file changes, not when a function
it calls does (a law, an event helper): ``_guard_cache`` drops rodjit's cache files whenever
any source of the compiled layers differs from the last process that compiled them.
"""
from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numba
from numba.core import caching
from numba.core.cpu import CPUTargetOptions

JIT_OPTIONS = {"cache": True, "error_model": "numpy", "nogil": True}

kernel = numba.njit(**JIT_OPTIONS)

# Kernels called on every step of the time loop (the step, its forces and sub-steps, the
# event and step-size helpers) are also marked for inlining into the loop (LLVM
# alwaysinline): a step then makes no calls and passes no arrays, which matters for short
# rods, where the work per step is a few dozen flops (N = 5: ~3x fewer ns per step;
# benchmarks/bench_scipy.py).  Numba without the option compiles them as plain kernels.
_CAN_FORCE_INLINE = hasattr(CPUTargetOptions, "forceinline")
step_kernel = (numba.njit(**JIT_OPTIONS, forceinline=True) if _CAN_FORCE_INLINE else kernel)

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


def _guard_cache() -> None:
    root = Path(__file__).resolve().parent
    digest = hashlib.sha1(numba.__version__.encode())
    compiled = [root / "_jit.py"] + [p for d in COMPILED_PACKAGES for p in (root / d).rglob("*.py")]
    for p in sorted(compiled):
        digest.update(p.relative_to(root).as_posix().encode())
        digest.update(p.read_bytes())
    stamp_dir = (Path(numba.config.CACHE_DIR) / root.relative_to(root.anchor)
                 if numba.config.CACHE_DIR else root / "__pycache__")
    stamp = stamp_dir / "rodjit-sources.sha1"
    try:
        if stamp.read_text() == digest.hexdigest():
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
        tmp.write_text(digest.hexdigest())
        os.replace(tmp, stamp)
    except OSError:
        pass  # read-only install: Numba falls back to its user-wide cache


_guard_cache()
