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

With ``--evaluate``: the runs of a table fit (``rodjit.fit_table``: 6 rows of
paper-mu100 over impact speeds 2–8 m/s, at 3 parameter vectors, 6 times: 108 runs),
evaluated as a fit does (its observables are sweep summary columns: the batch engine)
against a run file each (``analysis.evaluate`` without ``columns``), in alternating
pairs on 2 workers.

    python benchmarks/bench_fit.py [--full] [--evaluate]
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


def evaluate_paths(repeat: int = 3) -> dict:
    """A table fit's runs on the batch engine against a run file each (module docstring)."""
    from rodjit.analysis.evaluate import evaluate

    _util.header("a table fit's 108 runs: batch engine against a run file each (2 jobs)")
    base = rodjit.load_preset("paper-mu100").override({"time.t_end": 1.0,
                                                       "initial.height": 0.01})
    configs = [base.override({"initial.impact_speed": v, "rod.mu": mu,
                              "floor.kappa_b": kb})
               for _ in range(6) for mu, kb in ((150.0, 2e3), (150.15, 2e3), (150.0, 2002.0))
               for v in (2.0, 3.0, 4.0, 5.0, 6.0, 8.0)]
    columns = ["restitution_first", "contact_time_first"]
    evaluate(configs[:4], jobs=JOBS, columns=columns)    # kernels loaded before timing
    t_batch, t_files = [], []
    for _ in range(repeat):
        t_batch.append(_util.timed(lambda: evaluate(configs, jobs=JOBS, columns=columns))[0])
        t_files.append(_util.timed(lambda: evaluate(configs, jobs=JOBS))[0])
    b, f = float(np.median(t_batch)), float(np.median(t_files))
    print(_util.table([["batch engine", len(configs), b, 1e3 * b / len(configs), 1.0],
                       ["a run file each", len(configs), f, 1e3 * f / len(configs), f / b]],
                      ["path", "runs", "time [s]", "ms per run", "× batch engine"]))
    return {"runs": len(configs), "batch_time": b, "files_time": f, "speedup": f / b}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--full", action="store_true", help="run every grid point")
    ap.add_argument("--evaluate", action="store_true",
                    help="only a table fit's runs: batch engine against a run file each")
    args = ap.parse_args()
    if args.evaluate:
        out = evaluate_paths()
        print(f"   -> {_util.save('fit_evaluate', out)}")
        return out
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
