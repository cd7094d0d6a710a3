"""Streaming overhead: a run writing snapshots every 1e-3 simulated seconds to HDF5 against
the same run with no output at all (target: under 10% extra wall time).

All are measured here, in this process, after a warm-up that loads the compiled kernels;
each figure is the best of ``--repeat`` runs taken in turns.  The breakdown separates the
extra steps taken to land exactly on the output times from the cost of writing the file.

    python benchmarks/streaming_overhead.py [--N 200] [--t-end 30] [--repeat 5]

The time inside the writer (creating the file, appending, checkpointing, closing, the
summary) is wall and CPU time of the process's thread.  A file also has a fixed cost
(creating ~50 datasets with their dimension scales, two checkpoints, closing): measured
apart on a run of 1e-3 s, it is what dominates very short runs, and the default t_end (a
run of a few seconds) is where the per-snapshot cost of streaming shows.
"""
from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import rodjit
import rodjit.driver.files as files
from rodjit.driver.run import Run, Sink
from rodjit.output import hdf5
from rodjit.stepping import layout as L


def run_bare(config) -> tuple[float, float, int]:
    """Wall time, CPU time and steps of the compiled loop alone, output discarded."""
    t0, c0 = time.perf_counter(), time.process_time()
    run = Run(config)
    sink = Sink()
    run.start(sink)
    while run.advance(sink) != L.DONE:
        pass
    return time.perf_counter() - t0, time.process_time() - c0, run.steps


def run_file(config, path) -> tuple[float, float, int]:
    """The same for ``run_to_file`` into a new file (replacing a file costs the filesystem
    its own time, which is not the streaming's)."""
    path.unlink(missing_ok=True)
    t0, c0 = time.perf_counter(), time.process_time()
    s = rodjit.run_to_file(config, path)
    return time.perf_counter() - t0, time.process_time() - c0, s.steps


class WriterClock:
    """Wall and CPU time inside the HDF5 writer (creating, appending, checkpointing,
    closing, summarising), outermost calls only: the cost of streaming itself."""

    def __init__(self):
        self.wall = self.cpu = 0.0
        self._depth = 0
        for owner, name in ((files.run_writer, "create_run_file"), (files, "closed_summary"),
                            (hdf5.RunWriter, "snapshots"), (hdf5.RunWriter, "diagnostics"),
                            (hdf5.RunWriter, "episodes"), (hdf5.RunWriter, "bounces"),
                            (hdf5.RunWriter, "save"), (hdf5.RunWriter, "close")):
            setattr(owner, name, self._timed(getattr(owner, name)))

    def _timed(self, fn):
        def wrapper(*args, **kwargs):
            self._depth += 1
            t0, c0 = time.perf_counter(), time.thread_time()
            try:
                return fn(*args, **kwargs)
            finally:
                self._depth -= 1
                if self._depth == 0:
                    self.wall += time.perf_counter() - t0
                    self.cpu += time.thread_time() - c0
        return wrapper

    def measure(self, config, path) -> tuple[float, float]:
        """(wall, CPU) inside the writer for one run of ``config``."""
        wall, cpu = self.wall, self.cpu
        run_file(config, path)
        return self.wall - wall, self.cpu - cpu


def best_interleaved(fns, repeat):
    """Best (wall, cpu, steps) of each function, the functions taking turns so that a change
    in the machine's load hits all of them alike."""
    results = [[] for _ in fns]
    for _ in range(repeat):
        for fn, res in zip(fns, results):
            res.append(fn())
    return [(min(r[0] for r in res), min(r[1] for r in res), res[0][2]) for res in results]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--N", type=int, default=200)
    ap.add_argument("--t-end", type=float, default=30.0)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--integrator", default="verlet",
                    help="the stepping of the measured run (default verlet: the cheapest "
                         "steps, so the writer's share is the largest)")
    args = ap.parse_args()
    base = rodjit.Config().override({"rod.N": args.N, "time.t_end": args.t_end,
                                     "time.integrator": args.integrator,
                                     "output.diagnostics_interval": 0.0})
    none = base.override({"output.snapshot_interval": 0.0})
    snaps = base.override({"output.snapshot_interval": 1e-3})
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.h5"
        run_file(snaps, path)                       # warm-up: kernels from the cache
        measured = best_interleaved([lambda: run_bare(none), lambda: run_bare(snaps),
                                     lambda: run_file(snaps, path)], args.repeat)
        size = path.stat().st_size / 2**20
        clock = WriterClock()
        writer = [min(x) for x in
                  zip(*(clock.measure(snaps, path) for _ in range(args.repeat)))]
        tiny = snaps.override({"time.t_end": 1e-3})
        fixed = min(clock.measure(tiny, path)[1] for _ in range(args.repeat))
    (t_none, c_none, s_none), (t_land, c_land, s_land), (t_file, c_file, s_file) = measured
    n_snap = int(round(args.t_end / 1e-3)) + 1
    print(f"N = {args.N}, t_end = {args.t_end:g}, {n_snap} snapshots of {args.N + 1} nodes "
          f"({size:.1f} MiB file); best of {args.repeat}; wall and CPU time")
    rows = (("no output (compiled loop only)", t_none, c_none, s_none),
            ("snapshots every 1e-3, discarded", t_land, c_land, s_land),
            ("streamed to HDF5 (run_to_file)", t_file, c_file, s_file))
    for label, t, c, n in rows:
        print(f"  {label:<40}{t:8.3f} s {c:8.3f} s  {n:9d} steps  "
              f"{100 * (t / t_none - 1):+6.1f}%")
    print(f"time inside the HDF5 writer: {writer[0]:.3f} s wall, {writer[1]:.3f} s CPU = "
          f"{100 * writer[1] / t_none:.1f}% of the no-output run (summary included)")
    print(f"fixed cost of a file (a run of 1e-3 s, 2 snapshots): {1e3 * fixed:.1f} ms CPU; "
          f"per snapshot beyond it: {1e6 * (writer[1] - fixed) / n_snap:.2f} µs")
    print(f"streaming overhead (wall): {100 * (t_file / t_none - 1):+.1f}% (target < +10%), "
          f"of which landing on output times {100 * (t_land / t_none - 1):+.1f}% and writing "
          f"the file {100 * (t_file - t_land) / t_none:+.1f}%")
    print(f"CPU time of the whole process: {100 * (c_file / c_none - 1):+.1f}%")


if __name__ == "__main__":
    main()
