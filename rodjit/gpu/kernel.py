"""The CUDA kernel of a batch of sweep points: one thread per point, each running the
per-point driver ``stepping.trajectory.run_one`` (the CPU engine's, compiled for CUDA) on
its own state in ``cuda.local.array``.

A kernel is made per *family*: the classes of the six parameter tuples of the compiled loop
(scheme, control, system, rod law, floor law, observer: ``driver.setup.parameters``), the
kinds of their fields, and the node count N + 1 (local arrays need compile-time shapes).  Every
point's tuples travel as one row of a float64 array; the kernel rebuilds them field by
field (``stepping.packing``: an int or bool field is stored exactly as a double), so the
values of a sweep's parameters stay run-time values and one compile serves the whole grid.

The kernel's source is made here (``_source``) because the tuples' classes and field counts
are the family's; the model in it is the CPU's own code, retargeted (``retarget``).  Under
numba-cuda's simulator (``NUMBA_ENABLE_CUDASIM=1``) the same kernel runs as Python, and
``run_one`` and the loop are the CPU's compiled functions themselves: the simulator checks
the kernel's set-up, the drains and the host side; ``compile_ptx`` checks that all of it
compiles for the GPU.
"""
from __future__ import annotations

import contextlib
import sys
import threading
from typing import NamedTuple

from ..stepping import impact_stream as S
from ..stepping import layout as L
from ..stepping import packing as P
from ..stepping import trajectory as T
from ..stepping.arrays import BUFFERS, INPUTS, SPEC, RunArrays, shape
from ..stepping.observers import state_size
from ..stepping.schemes import work_rows
from ._cuda import import_cuda

__all__ = ["Family", "family_of", "make_kernel", "compile_ptx", "simulated",
           "deep_call", "N_MAX"]

# the largest rod (segments N) a thread runs: its state, trial states, integrator scratch
# and interpolation rows are (8 + work rows) × (N + 1) doubles of local memory (3 kB for the
# energy integrator at N = 32, 7 kB at N = 64), beyond which one thread per trajectory
# spills more than it computes
N_MAX = 64

class Family(NamedTuple):
    """What a compiled kernel depends on (module docstring)."""

    classes: tuple          # the six parameter tuples' classes
    kinds: tuple            # per tuple, the kind of each field: "f", "i" or "b"
    n1: int                 # nodes N + 1
    work_rows: int
    observed: int           # entries of the observer's array (``observers.state_size``)


def family_of(params) -> Family:
    """The family of a point's parameter tuples ``params`` (``driver.run.parameters``);
    a TypeError for a field that is not a Python float, int or bool (``packing.kinds``)."""
    return Family(tuple(type(t) for t in params), P.kinds(params, exact=True),
                  int(params[2].n) + 1, int(work_rows(params[0])),
                  int(state_size(params[5])))


def simulated() -> bool:
    """Whether numba-cuda runs kernels in its simulator (``NUMBA_ENABLE_CUDASIM=1``)."""
    from numba.cuda import config

    return bool(getattr(config, "ENABLE_CUDASIM", False))


def _source(family: Family) -> str:
    names = [f"C{k}" for k in range(len(family.classes))]
    fields = [f"    t{k} = {x}"
              for k, x in enumerate(P.rebuild_source(family.kinds, "p", names))]
    n1 = family.n1
    # the run's arrays (``stepping.arrays``): the output buffers are the point's rows of
    # the kernel's arguments, the inputs those arguments themselves (the same for every
    # thread of a launch), the others local arrays, zeroed, then the state's u and v rows,
    # the clock and ev rows from the point's
    size = {"n1": n1, "work": family.work_rows, "observed": max(1, family.observed)}
    local = []
    for name in RunArrays._fields:
        if name in BUFFERS + INPUTS:
            continue
        dt, _ = SPEC[name]
        dims = shape(name, size)
        local.append(f"    {name} = cuda.local.array({dims}, {dt.name})")
        index = ", ".join(f"j{d}" for d in range(len(dims)))
        for d, n in enumerate(dims):
            local.append(f"    {'    ' * d}for j{d} in range({n}):")
        local.append(f"    {'    ' * len(dims)}{name}[{index}] = 0")
    buffers = ", ".join(BUFFERS + INPUTS)
    fields_of = ", ".join(f"{name}[i]" if name in BUFFERS else name
                          for name in RunArrays._fields)
    nl = "\n"
    return f"""
def sweep_kernel(params, state0, clock0, ev0, {buffers},
                 bounce_out, fout, iout, max_steps):
    i = cuda.grid(1)
    if i >= params.shape[0]:
        return
    p = params[i]
{nl.join(fields)}
{nl.join(local)}
    imp = cuda.local.array({S.SIZE}, float64)
    for j in range({n1}):
        state[0, j] = state0[i, 0, j]
        state[1, j] = state0[i, 1, j]
    for j in range({L.CLOCK_SIZE}):
        clock[j] = clock0[i, j]
    for j in range({L.EV_SIZE}):
        ev[j] = ev0[i, j]
    arrays = RunArrays({fields_of})
    run_one(t0, t1, t2, t3, t4, t5, arrays, imp, bounce_out[i], fout[i], iout[i], max_steps)
"""


def _namespace(family: Family, cuda, run_one) -> dict:
    from numba import float64, int64

    ns = {"cuda": cuda, "float64": float64, "int64": int64, "run_one": run_one,
          "RunArrays": RunArrays}
    ns.update({f"C{k}": cls for k, cls in enumerate(family.classes)})
    return ns


_LOCK = threading.Lock()
_KERNELS: dict = {}


def kernel_function(family: Family, cuda, run_one):
    """The Python function of a family's kernel, reading ``cuda`` and ``run_one`` as
    globals (the simulator replaces a kernel's global ``cuda`` by its own)."""
    ns = _namespace(family, cuda, run_one)
    exec(compile(_source(family), f"<rodjit.gpu kernel N={family.n1 - 1}>", "exec"), ns)
    return ns["sweep_kernel"]


def make_kernel(family: Family):
    """The family's kernel, compiled once per process (on its first launch)."""
    cuda = import_cuda()
    with _LOCK:
        got = _KERNELS.get(family)
        if got is None:
            got = _KERNELS[family] = deep_call(_new_kernel, family, cuda)
        return got


def _new_kernel(family: Family, cuda):
    if simulated():
        run_one = _simulated_run_one
    else:
        from .retarget import Retarget

        run_one = Retarget(cuda).device(T.run_one)
    return cuda.jit(kernel_function(family, cuda, run_one))


def _simulated_run_one(*args):
    """``run_one`` in the simulator: its device arrays unwrapped to the NumPy arrays they
    hold, so the loop's kernels run compiled for the CPU (they cannot take the simulator's
    array objects), on the thread's own rows."""
    def host(a):
        if isinstance(a, RunArrays):
            return RunArrays(*map(host, a))
        return getattr(a, "_ary", a)

    return T.run_one(*map(host, args))


# A GPU compile nests deeply: each device function is typed and compiled inside its
# caller's typing (run_one -> advance -> the step -> the rates -> a law), dozens of Numba's
# frames a level, and a compile error is re-raised through every level.  The integrators'
# deepest chains come near 5000 Python frames, past the default limit of 1000 and past any
# limit left to a caller whose own stack is already deep (a test runner's workers); so the
# compile runs on a thread of its own, from an empty stack, with room for COMPILE_FRAMES
# frames and a C stack of COMPILE_STACK bytes for them (about 13 kB a frame, several times
# what CPython and Numba's C calls take; the 8 MB of a main thread would hold about 1000)
COMPILE_FRAMES = 20_000
COMPILE_STACK = 256 << 20

_DEEP_LOCK = threading.Lock()
_DEEP = threading.local()


def deep_call(fn, *args, **kwargs):
    """``fn(*args, **kwargs)`` run on a fresh thread with a COMPILE_STACK-byte stack and Python's
    recursion limit raised to COMPILE_FRAMES (restored after): its result, or its exception
    raised here.  Calls are serialised (the limit and the stack size are the process's);
    a call from inside one runs at once on its thread."""
    if getattr(_DEEP, "inside", False):
        return fn(*args, **kwargs)
    box: dict = {}

    def work():
        _DEEP.inside = True
        try:
            box["value"] = fn(*args, **kwargs)
        except BaseException as exc:    # re-raised in the caller, KeyboardInterrupt too
            box["error"] = exc

    with _DEEP_LOCK:
        old_limit = sys.getrecursionlimit()
        old_size = threading.stack_size()
        # raised before the thread starts: a thread checks the process's limit when it
        # reaches its own, so a limit raised after the start races with a busy machine
        sys.setrecursionlimit(max(old_limit, COMPILE_FRAMES))
        try:
            try:
                threading.stack_size(COMPILE_STACK)
            except (ValueError, RuntimeError):  # a platform without a settable stack size
                pass
            try:
                worker = threading.Thread(target=work, name="rodjit-gpu-compile",
                                          daemon=True)
                worker.start()
            finally:
                threading.stack_size(old_size)
            worker.join()
        finally:
            sys.setrecursionlimit(old_limit)
    if "error" in box:
        raise box["error"]
    return box.get("value")


class _Device(NamedTuple):
    compute_capability: tuple


@contextlib.contextmanager
def _compute_capability(cc):
    """Compile device functions for ``cc`` without asking the driver.

    numba-cuda compiles a device function called from a kernel for the current device's
    compute capability (``dispatcher.get_current_device``), which needs a GPU and its
    driver even inside ``compile_ptx``.  Here that question is answered with ``cc``, so
    the whole kernel, device functions included, compiles to PTX on a machine without
    either (the tests, CI)."""
    from numba.cuda import dispatcher

    original = dispatcher.get_current_device
    dispatcher.get_current_device = lambda: _Device(tuple(cc))
    try:
        yield
    finally:
        dispatcher.get_current_device = original


def signature(family: Family):
    """The Numba signature of a family's kernel (for ``compile_ptx``): its arguments as
    ``_source`` makes them, the output buffers as a row of each per point, the inputs
    whole."""
    from numba import float64, int64, types, void

    def rows(name):
        dt, dims = SPEC[name]
        return types.Array(float64 if dt.name == "float64" else int64, len(dims) + 1, "C")

    return void(float64[:, ::1], float64[:, :, ::1], float64[:, ::1], float64[:, ::1],
                *map(rows, BUFFERS), *(float64[::1] for _ in INPUTS), float64[:, :, ::1],
                float64[:, ::1], int64[:, ::1],
                int64)


def compile_ptx(family: Family, cc=(9, 0)) -> str:
    """PTX of a family's kernel for compute capability ``cc``, compiled without a GPU:
    the real compile of everything the kernel runs (what the simulator cannot check)."""
    with _LOCK:
        return deep_call(_compile_ptx, family, tuple(cc))


def _compile_ptx(family: Family, cc: tuple) -> str:
    from .retarget import Retarget

    cuda = import_cuda()
    with _compute_capability(cc):
        run_one = Retarget(cuda).device(T.run_one)
        ptx, _ = cuda.compile_ptx(kernel_function(family, cuda, run_one), signature(family),
                                  cc=cc)
    return ptx
