"""The GPU engine's host side: check a batch of points, pack it, launch its kernel, and
turn what the threads left into a ``sweeps.batch.BatchResult``.

Every point starts from exactly the arrays the driver's ``Run`` starts from (parameter
tuples, initial state, clock, flight time), made by the same set-up (``driver.setup``), so
a thread starts where ``rodjit run`` would; it runs the CPU engine's per-point driver
(``stepping.trajectory.run_one``, compiled for CUDA: ``kernel``), and its results are read
by the CPU engine's decoder (``sweeps.decode``): the same summary columns, first-impact
columns and bounce tables.

A thread keeps BOUNCE_ROWS bounce rows; a point with more stops when they are full
(``stepping.trajectory``), and is run again, whole, on the CPU engine
(``sweeps.ensemble.run_starts``), which keeps every bounce: its row and bounce table are
the CPU's.  ``compile_time``, ``run_time`` and ``wall_time`` of a point are its equal
share of its batch's.
"""
from __future__ import annotations

import os
import re
import socket
import time
import warnings

import numpy as np

from ..config import ModelWarning
from ..driver.run import NODE_STEPS_PER_CALL
from ..driver.setup import start, starts
from ..model.laws import get_law
from .._jit import Kernel
from ..stepping.arrays import BUFFERS, SPEC, shape
from ..stepping import trajectory as T
from ..stepping.packing import pack
from ..sweeps import decode
from ..sweeps.batch import BatchResult
from ..sweeps.ensemble import run_starts
from ..sweeps.point import SUMMARY_COLUMNS, empty_columns, pass_on, summary_columns
from ._cuda import CudaUnavailable, import_cuda
from .kernel import N_MAX, deep_call, family_of, make_kernel, signature, simulated

__all__ = ["run_batch", "check_device", "check_point", "prepare", "resolve_device",
           "GPU_INTEGRATORS",
           "GpuUnsupported", "N_MAX"]

# the integrators whose loop compiles for the GPU (tests/test_gpu_ptx.py compiles each)
GPU_INTEGRATORS = ("energy", "dp54", "dop853", "verlet", "semi-implicit", "radau5")
BOUNCE_ROWS = 64            # bounce rows a thread keeps (a point with more: the CPU's)
EVENT_ROWS = 16             # local buffer rows of episodes and of bounces between drains
THREADS = 128               # threads per block
MEMORY = 2 << 30            # bytes of output buffers per launch (the batch is split)


class GpuUnsupported(ValueError):
    """A point the GPU engine cannot run (N, integrator, law): one line saying why."""


def resolve_device(device: str | None) -> str:
    """``"cpu"`` or ``"cuda"`` for ``device`` (None/"cpu", "cuda", "auto": the GPU when
    numba-cuda finds one, else the CPU); ValueError for another value."""
    if device in (None, "cpu"):
        return "cpu"
    if device not in ("cuda", "auto"):
        raise ValueError(f"device = {device!r} is not one of 'cpu', 'cuda', 'auto'")
    if device == "auto":
        try:
            check_device()
        except CudaUnavailable:
            return "cpu"
    return "cuda"


def check_device() -> None:
    """CudaUnavailable (one line) unless kernels can run: numba-cuda installed, and a GPU
    or the simulator (``NUMBA_ENABLE_CUDASIM=1``)."""
    cuda = import_cuda()
    if simulated():
        return
    if not cuda.is_available():
        raise CudaUnavailable("device = 'cuda': no CUDA GPU is available here (numba-cuda "
                              "finds none); use device = 'cpu'")


def check_point(config) -> None:
    """GpuUnsupported (one line) for a point the GPU engine does not run."""
    config = config.resolve()
    n = config.rod.N
    if n > N_MAX:
        raise GpuUnsupported(f"rod.N = {n} is out of range for device = 'cuda' (1 to "
                             f"{N_MAX}: one thread runs one rod); use device = 'cpu'")
    if config.time.integrator not in GPU_INTEGRATORS:
        raise GpuUnsupported(f"time.integrator = {config.time.integrator!r} has no GPU "
                             f"version; choose one of {list(GPU_INTEGRATORS)} or device = "
                             f"'cpu'")
    for kind, name in (("rod", config.rod.law), ("floor", config.floor.law)):
        law = get_law(kind, name)
        parts = [law.value, law.deriv, law.primitive, law.lower, law.deriv_max,
                 law.difference, law.extension, law.extension_deriv]
        if not all(p is None or isinstance(p, Kernel) for p in parts):
            raise GpuUnsupported(f"{kind}.law = {name!r} has no GPU version: its functions "
                                 f"must be rodjit kernels (rodjit.laws.law_kernel) to be "
                                 f"compiled for the GPU; use device = 'cpu'")


def _capacities(run) -> tuple[int, int]:
    """Snapshot and diagnostics rows between drains: at least what one dense-output step
    writes (``Control.dense_snapshots``, as the driver's buffers)."""
    return max(4, run.ctrl.dense_snapshots), max(16, run.ctrl.dense_diagnostics)


def _times(runs) -> np.ndarray:
    """The listed snapshot times (``output.times``) of a launch's points, the same for all
    (``run_batch`` groups its points so): the kernel's ``times`` input, one array for every
    thread, so a long list costs its size once, not once per point (a placeholder row
    where there are none)."""
    times = runs[0].config.output.times
    return np.array(times if times else (np.inf,), dtype=np.float64)


def _launch(runs, cuda):
    """Run points of one family on the device; ``(fout, iout, bounce rows, compile s,
    run s)``."""
    fam = family_of(runs[0].params())
    n1 = fam.n1
    cs, cd = _capacities(runs[0])
    n = len(runs)
    # the points share their parameter tuples where they agree (``driver.setup``): each
    # packed once
    packed: dict = {}
    rows = []
    for r in runs:
        row = []
        for t in r.params():
            got = packed.get(id(t))
            if got is None:
                got = packed[id(t)] = pack((t,), exact=True)
            row.extend(got)
        rows.append(row)
    params = np.array(rows, dtype=np.float64).reshape(n, -1)
    state0 = np.ascontiguousarray(np.stack([r.state for r in runs]))
    clock0 = np.stack([r.clock for r in runs])
    ev0 = np.stack([r.ev() for r in runs])
    k = make_kernel(fam)
    d = cuda.to_device
    # the output buffers of the points' arrays (``stepping.arrays``): a row of each per point
    size = {"n1": n1, "snapshots": cs, "diagnostics": cd, "events": EVENT_ROWS}
    buffers = [cuda.device_array((n, *shape(name, size)), SPEC[name][0]) for name in BUFFERS]
    out = [d(params), d(state0), d(clock0), d(ev0), *buffers, d(_times(runs)),
           cuda.device_array((n, BOUNCE_ROWS, T.BOUT_SIZE)),
           cuda.device_array((n, T.fout_width(runs[0].obs))),
           d(np.zeros((n, T.I_SIZE), np.int64))]
    threads = min(THREADS, n) if not simulated() else min(32, n)
    max_steps = max(1, NODE_STEPS_PER_CALL // n1)
    t0 = time.perf_counter()
    _compile(k, fam, runs[0].config)
    t1 = time.perf_counter()
    k[(n + threads - 1) // threads, threads](*out, max_steps)
    brows, fout, iout = (a.copy_to_host() for a in out[-3:])
    t2 = time.perf_counter()
    return fout, iout, brows, t1 - t0, t2 - t1


def _compile(k, fam, config) -> None:
    """Compile a family's kernel (once per process: later calls find it compiled), or
    GpuUnsupported naming the model that CUDA cannot compile."""
    if simulated():
        return
    try:
        deep_call(k.compile, signature(fam))
    except Exception as exc:
        raise GpuUnsupported(f"the GPU cannot compile this model (rod.law = "
                             f"{config.rod.law!r}, floor.law = {config.floor.law!r}, "
                             f"time.integrator = {config.time.integrator!r}): {reason(exc)}; "
                             f"use device = 'cpu'") from None


def prepare(config) -> None:
    """Check ``config`` (``check_point``) and compile its kernel, before a sweep writes
    anything: a model CUDA cannot compile is refused in one line, not after the file is
    made.  A point that cannot start is left to fail as a point."""
    check_point(config)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ModelWarning)
            s = start(config)
    except Exception:
        return
    fam = family_of(s.params())
    _compile(make_kernel(fam), fam, config)


# the lines of a Numba error that name the cause, not the chain of calls that led to it
_CAUSES = ("Unknown attribute", "Untyped global name", "Use of unsupported",
           "Cannot determine Numba type", "Invalid use of", "NotImplementedError",
           "KeyError", "Unsupported", "Cannot unify", "unsupported")


def reason(exc) -> str:
    """The line of a Numba compile error that says what failed: the innermost cause where
    one is named (an attribute or global CUDA cannot type, an unsupported call), else the
    first line past the compiler pass names; colour codes removed."""
    lines = [re.sub(r"\x1b\[[0-9;]*m", "", x).strip() for x in str(exc).splitlines()]
    lines = [x for x in lines if x and not x.startswith(("Failed in", "During:"))]
    for x in lines:
        if x.startswith(_CAUSES):
            return x
    return lines[0] if lines else type(exc).__name__


def run_batch(configs, index) -> BatchResult:
    """Run the points ``configs`` (grid indices ``index``) on the GPU; a point that cannot
    start (its set-up raises) is failed with the reason, as a CPU point is.  ``worker``
    holds the device and the batch's seconds: ``setup_time`` (the points' set-up,
    ``driver.setup``, on the host), ``compile_time`` (the kernels, first batch of a family
    in a process), ``kernel_time`` (the launches and the copies of their results back) and ``wall_time``.

    Raises CudaUnavailable or GpuUnsupported (one line) before anything runs."""
    cuda = import_cuda()
    check_device()
    for c in configs:
        check_point(c)
    t_start = time.perf_counter()
    n = len(configs)
    cols = empty_columns(n, summary_columns(configs[0]) if n else SUMMARY_COLUMNS)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ModelWarning)
        runs: list = starts(configs)
    said: list[str] = list(pass_on(caught))
    for j, r in enumerate(runs):
        if isinstance(r, Exception):     # as run_point: the point fails, the batch goes on
            cols["status"][j] = "failed"
            cols["message"][j] = f"{type(r).__name__}: {r}"
            runs[j] = None
    t_setup = time.perf_counter() - t_start
    groups: dict = {}
    families: dict = {}
    for j, r in enumerate(runs):
        if r is not None:
            ids = tuple(map(id, r.params()))
            fam = families.get(ids)
            if fam is None:
                fam = families[ids] = family_of(r.params())
            # one listed-times array per launch, shared by its threads (``_times``)
            groups.setdefault((fam, r.config.output.times), []).append(j)
    rows_of: list[list] = [[] for _ in range(n)]
    again: list = []            # points whose bounce rows filled: the CPU engine's
    compile_s = run_s = 0.0
    for members in groups.values():
        per = _bytes_per_point(runs[members[0]])
        step = max(1, int(MEMORY // per))
        for lo in range(0, len(members), step):
            part = np.asarray(members[lo:lo + step], dtype=np.int64)
            fout, iout, brows, c_s, r_s = _launch([runs[j] for j in part], cuda)
            compile_s += c_s
            run_s += r_s
            stop = decode.stopped(iout)
            again.extend((int(j), runs[j]) for j in part[stop])
            done = np.flatnonzero(~stop)
            decode.summarize(cols, part[done], [runs[j] for j in part[done]], fout[done],
                             iout[done])
            decode.take_rows(rows_of, part[done], brows.reshape(-1, T.BOUT_SIZE),
                             iout[done], first=done * BOUNCE_ROWS)
    if again:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ModelWarning)
            run_starts(again, cols, rows_of)
        said.extend(pass_on(caught))
    bounces, counts = decode.bounce_tables(cols, rows_of)
    wall = time.perf_counter() - t_start
    cols["compile_time"][:] = compile_s / max(n, 1)
    cols["run_time"][:] = run_s / max(n, 1)
    cols["wall_time"][:] = wall / max(n, 1)
    worker = {**_worker(cuda), "points": n, "setup_time": t_setup,
              "compile_time": compile_s, "kernel_time": run_s, "wall_time": wall}
    return BatchResult(np.asarray(index, dtype=np.int64), cols, bounces, counts,
                       tuple(dict.fromkeys(said)), worker)


def _bytes_per_point(run) -> int:
    cs, cd = _capacities(run)
    n1 = run.system.n + 1
    size = {"n1": n1, "snapshots": cs, "diagnostics": cd, "events": EVENT_ROWS}
    buffers = sum(SPEC[name][0].itemsize * int(np.prod(shape(name, size)))
                  for name in BUFFERS)
    return buffers + 8 * (BOUNCE_ROWS * T.BOUT_SIZE + 64 + 2 * n1)


def _worker(cuda) -> dict:
    name = "simulator"
    if not simulated():
        name = cuda.get_current_device().name
        name = name.decode() if isinstance(name, bytes) else str(name)
    return {"pid": os.getpid(), "host": socket.gethostname(), "device": name}
