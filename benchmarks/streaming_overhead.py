"""Streaming overhead: a run writing snapshots every 1e-3 simulated seconds to HDF5 against
the same run with no output at all (target: under 10% extra wall time).

Both are measured here, in this process, after a warm-up that loads the compiled kernels;
each figure is the best of ``--repeat`` runs.  The breakdown separates the extra steps
taken to land exactly on the output times from the cost of writing the file.

    python benchmarks/streaming_overhead.py [--N 200] [--t-end 5] [--repeat 5]
"""
from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import rodjit
from rodjit.driver.run import Run, Sink
from rodjit.stepping import layout as L


def run_bare(config) -> tuple[float, int]:
    """Wall time and steps of the compiled loop alone, output discarded."""
    t0 = time.perf_counter()
    run = Run(config)
    sink = Sink()
    run.start(sink)
    while run.advance(sink) != L.DONE:
        pass
    return time.perf_counter() - t0, run.steps


def run_file(config, path) -> tuple[float, int]:
    t0 = time.perf_counter()
    s = rodjit.run_to_file(config, path, overwrite=True)
    return time.perf_counter() - t0, s.steps


def best(fn, repeat):
    results = [fn() for _ in range(repeat)]
    return min(r[0] for r in results), results[0][1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--N", type=int, default=200)
    ap.add_argument("--t-end", type=float, default=5.0)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    base = rodjit.Config().override({"rod.N": args.N, "time.t_end": args.t_end,
                                     "output.diagnostics_interval": 0.0})
    none = base.override({"output.snapshot_interval": 0.0})
    snaps = base.override({"output.snapshot_interval": 1e-3})
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.h5"
        run_file(snaps, path)                       # warm-up: kernels from the cache
        t_none, s_none = best(lambda: run_bare(none), args.repeat)
        t_land, s_land = best(lambda: run_bare(snaps), args.repeat)
        t_file, s_file = best(lambda: run_file(snaps, path), args.repeat)
        size = path.stat().st_size / 2**20
    n_snap = int(round(args.t_end / 1e-3)) + 1
    print(f"N = {args.N}, t_end = {args.t_end:g}, {n_snap} snapshots of {args.N + 1} nodes "
          f"({size:.1f} MiB file); best of {args.repeat}")
    print(f"  no output (compiled loop only)        {t_none:8.3f} s  {s_none:9d} steps")
    print(f"  snapshots every 1e-3, discarded       {t_land:8.3f} s  {s_land:9d} steps")
    print(f"  snapshots every 1e-3, streamed to HDF5 {t_file:7.3f} s  {s_file:9d} steps")
    print(f"streaming overhead: {100 * (t_file / t_none - 1):+.1f}% wall time "
          f"(target < +10%), of which landing on output times {100 * (t_land / t_none - 1):+.1f}%"
          f" and writing the file {100 * (t_file - t_land) / t_none:+.1f}%")


if __name__ == "__main__":
    main()
