"""Calibration: time to a fitted viscosity against a plain grid search of the same accuracy.

The paper's setting (data/paper_mu100.toml) at N = 100, run to t_end = 0.8 s (the first
macroscopic contact ends before 0.6 s at every μ of the bracket): find μ in [0, 1] with
restitution_first = 0.8 (at N = 100 the restitution falls from 0.85 at μ = 0 to 0.65 at
μ = 1; at large μ it stays below 0.65 up to μ = 3000).

1. ``rodjit.fit`` on 2 worker processes: a parallel scan of 8 values, then Illinois false
   position (one run per iteration, in this process) to |e − 0.8| ≤ 1e-4.
2. The grid search a user would write instead, with the same accuracy: grid spacing
   Δμ = 2·1e-4/|de/dμ| (the fit's sensitivity at its answer), so that the grid point
   nearest to the crossing is within 1e-4 of the target; its points run by
   ``rodjit.sweep`` on 2 worker processes.  With ``--full`` every grid point runs; without
   it, SAMPLE points spread evenly over the grid run and the grid's time is their time
   × (grid size / SAMPLE) (printed as an estimate).

    python benchmarks/bench_fit.py [--full]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _util  # noqa: E402

import rodjit  # noqa: E402
from rodjit.analysis.fit import fit  # noqa: E402

BRACKET = (0.0, 1.0)
TARGET = 0.8
FTOL = 1e-4
SAMPLE = 32
JOBS = 2


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--full", action="store_true", help="run every grid point")
    args = ap.parse_args()
    _util.header("rodjit.fit against a grid search (paper setting, N = 100, target e = 0.8)")
    base = rodjit.load_preset("paper-mu100").override(
        {"rod.N": 100, "time.t_end": 0.8, "output.snapshot_interval": 0.0})
    rodjit.simulate(base.override({"time.t_end": 0.01}))   # kernels loaded before timing
    t0 = time.perf_counter()
    res = fit("rod.mu", {"restitution_first": TARGET}, base, bracket=BRACKET, ftol=FTOL,
              jobs=JOBS)
    t_fit = time.perf_counter() - t0
    print(f"   {res!r}")
    spacing = 2 * FTOL / abs(res.sensitivity)
    n_grid = int(np.ceil((BRACKET[1] - BRACKET[0]) / spacing)) + 1
    grid = np.linspace(*BRACKET, n_grid)
    run = grid if args.full or n_grid <= SAMPLE else grid[np.linspace(0, n_grid - 1, SAMPLE)
                                                          .round().astype(int)]
    t0 = time.perf_counter()
    table = rodjit.sweep(base, {"rod.mu": [float(x) for x in run]}, jobs=JOBS,
                         handle_signals=False)
    t_run = time.perf_counter() - t0
    t_grid = t_run * n_grid / len(run)
    e = np.asarray(table.columns["restitution_first"], float)
    print(_util.table([["rodjit.fit", res.evaluations, t_fit, 1.0],
                       ["grid search" + ("" if len(run) == n_grid else " (estimate)"), n_grid,
                        t_grid, t_grid / t_fit]],
                      ["method", "runs", "time [s]", "× fit's time"]))
    print(f"   grid spacing Δμ = {spacing:.3g} for |e − {TARGET}| ≤ {FTOL:g} "
          f"(de/dμ = {res.sensitivity:.3g}); {len(run)} of {n_grid} grid points run in "
          f"{t_run:.1f} s; their restitutions span {np.nanmin(e):.4f} .. {np.nanmax(e):.4f}")
    out = {"mu": res.value, "restitution": res.achieved, "sensitivity": res.sensitivity,
           "fit_runs": res.evaluations, "fit_time": t_fit, "grid_points": n_grid,
           "grid_points_run": len(run), "grid_time": t_grid, "speedup": t_grid / t_fit,
           "grid_estimated": len(run) != n_grid}
    path = _util.save("fit", out)
    print(f"   -> {path}")
    return out


if __name__ == "__main__":
    main()
