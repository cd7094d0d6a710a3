"""The GPU engine's host side: check a batch of points, pack it, launch its kernel, and
turn what the threads left into a ``sweeps.batch.BatchResult``.

Every point starts from exactly the arrays the driver's ``Run`` starts from (parameter
tuples, initial state, clock, flight time), made by the same set-up (``driver.setup``), so
a thread starts where ``rodjit run`` would; it runs the CPU's loop (``kernel``, ``trajectory``), and its summary row is made here by the same
functions as a CPU point's (``records.extremes.Extremes``, ``records.bounces.bounce_table``,
``sweeps.point.bounce_values``, ``Run.failure_message``).

The first-impact columns (``records.impact.IMPACT_COLUMNS``) come from the values each
thread streams from its diagnostics rows (``stepping.impact_stream``, as the CPU engine
does), turned into columns by ``records.impact.impact_columns``.  ``compile_time``,
``run_time`` and ``wall_time`` of a point are its equal share of its batch's.
"""
from __future__ import annotations

import math
import os
import re
import socket
import time
import types
import warnings

import numpy as np

from ..config import ModelWarning
from ..driver.run import NODE_STEPS_PER_CALL, Run
from ..driver.setup import start, starts
from ..model.laws import get_law
from .._jit import Kernel
from ..records.bounces import bounce_table
from ..records.columns import BOUNCE_COLUMNS
from ..records.extremes import Extremes
from ..records.impact import impact_columns
from ..stepping import impact_stream as S
from ..stepping import layout as L
from ..stepping.packing import pack
from ..sweeps.batch import BatchResult
from ..sweeps.ensemble import point_lift_energy
from ..sweeps.point import bounce_values, empty_columns, pass_on
from . import trajectory as T
from ._cuda import CudaUnavailable, import_cuda
from .kernel import N_MAX, deep_call, family_of, make_kernel, signature, simulated

__all__ = ["run_batch", "check_device", "check_point", "prepare", "resolve_device",
           "GPU_INTEGRATORS",
           "GpuUnsupported", "N_MAX"]

# the integrators whose loop compiles for the GPU (tests/test_gpu_ptx.py compiles each)
GPU_INTEGRATORS = ("energy", "dp54", "dop853", "verlet", "semi-implicit", "radau5")
BOUNCE_ROWS = 64            # bounce rows kept per point (more are counted and warned of)
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
    out = [d(params), d(state0), d(clock0), d(ev0),
           cuda.device_array((n, cs)), cuda.device_array((n, cs), np.int64),
           cuda.device_array((n, cs, n1)), cuda.device_array((n, cs, n1)),
           cuda.device_array((n, cd, len(L.DIAG_COLUMNS))),
           cuda.device_array((n, EVENT_ROWS, len(L.EPISODE_COLUMNS))),
           cuda.device_array((n, EVENT_ROWS, len(L.BOUNCE_ROW_COLUMNS))),
           cuda.device_array((n, BOUNCE_ROWS + 1, len(L.BOUNCE_ROW_COLUMNS))),
           cuda.device_array((n, T.F_SIZE)), cuda.device_array((n, T.I_SIZE), np.int64)]
    threads = min(THREADS, n) if not simulated() else min(32, n)
    max_steps = max(1, NODE_STEPS_PER_CALL // n1)
    t0 = time.perf_counter()
    _compile(k, fam, runs[0].config)
    t1 = time.perf_counter()
    k[(n + threads - 1) // threads, threads](*out, max_steps)
    fout, iout, brows = out[12].copy_to_host(), out[13].copy_to_host(), out[11].copy_to_host()
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


def _message(run, fout, code) -> str:
    if code == T.BAD_DIAGNOSTICS:
        return "a non-finite diagnostic value was computed; refusing to write it"
    view = types.SimpleNamespace(fail=fout[T.F_FAIL:T.F_FAIL + L.FAIL_SIZE], clock=run.clock,
                                 ctrl=run.ctrl, config=run.config, rod=run.rod,
                                 floor=run.floor)
    return Run.failure_message(view)


def _point(run, fout, iout, brows) -> tuple[dict, dict, str]:
    """A point's summary values (besides the times, the first-impact columns and those of
    its bounce table) and bounce table; a warning or ''."""
    nb = int(iout[T.I_BOUNCES])
    pending = None
    if iout[T.I_PENDING]:
        pending = (brows[nb], bool(iout[T.I_PENDING] == 2))
    bounces = bounce_table([brows[:nb]], pending)
    code = int(iout[T.I_CODE])
    ext = Extremes()
    ext.samples = int(iout[T.I_SAMPLES])
    ext.balance_max, ext.balance_min = float(fout[T.F_BAL_MAX]), float(fout[T.F_BAL_MIN])
    ext.kinetic_max = float(fout[T.F_KIN_MAX])
    ext.strain_min, ext.u0_min = float(fout[T.F_STRAIN_MIN]), float(fout[T.F_U0_MIN])
    ext.force_max = float(fout[T.F_FORCE_MAX])
    e = ext.with_bounces(bounces)

    def finite(x):
        return x if math.isfinite(x) else math.nan

    values = {"status": "completed" if code == L.DONE else "failed",
              "message": "" if code == L.DONE else _message(run, fout, code),
              "min_u0": finite(e.u0_min), "max_floor_force": finite(e.force_max),
              "min_strain": finite(e.strain_min),
              "energy_error": ext.energy_error(float(fout[T.F_E0])),
              "steps": int(iout[T.I_STEPS]), "rejected_steps": int(iout[T.I_REJECTED]),
              "t_final": float(fout[T.F_T]), "run_file": ""}
    said = ""
    if iout[T.I_DROPPED]:
        said = (f"the GPU engine keeps {BOUNCE_ROWS} bounce records per point: a point's "
                f"later bounces are counted in no column (n_bounces counts those kept)")
    return values, bounces, said


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
    cols = empty_columns(n)
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
            groups.setdefault(fam, []).append(j)
    tables: list = [None] * n
    compile_s = run_s = 0.0
    for members in groups.values():
        per = _bytes_per_point(runs[members[0]])
        step = max(1, int(MEMORY // per))
        for lo in range(0, len(members), step):
            part = members[lo:lo + step]
            fout, iout, brows, c_s, r_s = _launch([runs[j] for j in part], cuda)
            compile_s += c_s
            run_s += r_s
            for q, j in enumerate(part):
                values, tables[j], w = _point(runs[j], fout[q], iout[q], brows[q])
                for name, x in values.items():
                    cols[name][j] = x
                if w:
                    said.append(w)
            at = np.asarray(part, dtype=np.int64)
            impact_columns(cols, at, fout[:, T.F_IMPACT:T.F_IMPACT + S.OUT_SIZE],
                           iout[:, T.I_IMPACT],
                           lambda q: point_lift_energy(runs[part[q]].config,
                                                       runs[part[q]].rod))
            for j in part:
                got = bounce_values({"impact_status": cols["impact_status"][j]}, tables[j])
                for name, x in got.items():
                    cols[name][j] = x
    empty = bounce_table(())
    tables = [t if t is not None else empty for t in tables]
    counts = np.array([t["t_impact"].size for t in tables], dtype=np.int64)
    bounces = {name: np.concatenate([t[name] for t in tables]) for name in BOUNCE_COLUMNS}
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
    return 8 * (cs * (2 + 2 * n1) + cd * len(L.DIAG_COLUMNS)
                + EVENT_ROWS * (len(L.EPISODE_COLUMNS) + len(L.BOUNCE_ROW_COLUMNS))
                + (BOUNCE_ROWS + 1) * len(L.BOUNCE_ROW_COLUMNS) + 64 + 2 * n1)


def _worker(cuda) -> dict:
    name = "simulator"
    if not simulated():
        name = cuda.get_current_device().name
        name = name.decode() if isinstance(name, bytes) else str(name)
    return {"pid": os.getpid(), "host": socket.gethostname(), "device": name}
