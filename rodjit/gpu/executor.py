"""The GPU engine as a sweep executor: the points, in batches, through ``engine.run_batch``,
in this process; each batch's ``BatchResult`` goes to the sweep's driver
(``sweeps.run_sweep``), which writes it to the sweep file column by column, as it does a
CPU worker's batch."""
from __future__ import annotations

import importlib

from .engine import check_device, check_point, prepare, run_batch

__all__ = ["CudaExecutor", "check_grid", "cuda_executor", "sweep_device", "NotOnDevice"]

# points per batch: enough to fill an H100/H200 many times over (one thread each), few
# enough that a batch's results reach the sweep file every few seconds
BATCH_POINTS = 1 << 16
# keys whose values decide whether the GPU engine can run a point (``engine.check_point``)
_DECIDING = ("rod.N", "time.integrator", "rod.law", "floor.law")


def check_grid(base, grid) -> None:
    """GpuUnsupported/CudaUnavailable (one line) before a sweep starts: a GPU, and every
    point one the GPU engine runs (each point checked only if the grid sweeps a key that
    decides it, else the first)."""
    check_device()
    points = range(len(grid)) if any(k in _DECIDING for k in grid.keys) else range(1)
    for i in points:
        check_point(grid.config(base, i))


class CudaExecutor:
    """Runs a sweep's points on the GPU in batches of ``batch_points``."""

    name = "cuda"
    jobs = 1
    takes_points = True     # the driver hands it points; it batches them itself

    def __init__(self, batch_points: int = BATCH_POINTS):
        self.batch_points = int(batch_points)

    def _run(self, tasks):
        for task in tasks:
            for mod in task.laws:
                importlib.import_module(mod)
        return [run_batch([t.config for t in tasks], [t.index for t in tasks])]

    def results(self, tasks, total: int | None = None):
        batch = []
        for task in tasks:
            batch.append(task)
            if len(batch) >= self.batch_points:
                yield from self._run(batch)
                batch = []
        if batch:
            yield from self._run(batch)

    def close(self, cancel: bool = False) -> None:
        pass


class NotOnDevice(ValueError):
    """A sweep option the GPU engine cannot honour: a scheduler (it runs the points in this
    process) or run files (it keeps summaries only).

    Parameters
    ----------
    option : str
        ``"scheduler"`` or ``"save_runs"`` (``option``).
    value : object
        What was given for it (``value``).
    """

    def __init__(self, option: str, value) -> None:
        self.option, self.value = option, value
        super().__init__(self.worded(""))

    def worded(self, flag: str) -> str:
        """The message; ``flag`` (``" (--scheduler)"``) follows the option's name."""
        if self.option == "scheduler":
            return (f"scheduler = {self.value!r}{flag} cannot be used with device = 'cuda': "
                    f"the GPU engine runs the points in this process")
        return (f"save_runs{flag} is not available with device = 'cuda': the GPU engine "
                f"keeps summaries only; use device = 'cpu' for run files")

    def __reduce__(self):
        return type(self), (self.option, self.value)


def sweep_device(device: str | None, save_runs, scheduler=None) -> str:
    """The device a sweep runs on (``engine.resolve_device``), checked before anything is
    written: ``"cuda"`` needs numba-cuda and a GPU, writes no run files and runs in this
    process (no scheduler)."""
    from .engine import resolve_device

    device = resolve_device(device)
    if device == "cuda":
        check_device()
        if scheduler not in (None, "inline"):
            raise NotOnDevice("scheduler", scheduler)
        if save_runs is not None:
            raise NotOnDevice("save_runs", save_runs)
    return device


def cuda_executor(base, grid, first: int = 0) -> CudaExecutor:
    """The executor of a GPU sweep, once every point is checked (``check_grid``) and the
    kernel of point ``first`` (the first to run) is compiled (``engine.prepare``)."""
    check_grid(base, grid)
    prepare(grid.config(base, first))
    return CudaExecutor()
