"""The GPU engine (``rodjit sweep --device cuda``) on the paper's grid: trajectories per
second from 2^10 to 2^20 points, against diffrax ``jit(vmap)`` on the same GPU (when jax and
diffrax are installed) and the CPU path, with the accuracy of each.

Problem: the paper's rod, N = 5, T = 5 s, μ ∈ [0, 100] (linspace, n/2 values) × κ_b ∈
{1000, 3000}, every other key at its default, the default integrator (``energy``) and
``dp54``, default tolerances.

Measured, each in this one run:
- GPU engine (``rodjit.gpu.engine.run_batch``): the kernel's trajectories/s (launch and
  copy of the results back: ``kernel_time``), end to end with the host set-up of the
  points (``setup_time``), and the compile time apart
  (first launch of the kernel in the process).
- The host's set-up of the points alone (no GPU needed), 10^4 points: points/s of the
  set-up the engine uses (``rodjit.driver.setup.starts``) against one ``Run`` per point
  (the same set-up, and a run's buffers), the points' ``Config`` made beforehand and the
  set-up's kept pieces forgotten before each.
- CPU path: ``rodjit.sweep`` on every core (the process pool), 2^10 points.
- diffrax 0.7 (if importable): Tsit5 with a PID controller, ``jax.jit(jax.vmap(...))`` over
  (μ, κ_b), on the semi-discrete system of MODEL.md §2 written in JAX (benchmarks/jax_rod.py,
  γ = 0; shared with bench_sweep.py), compile
  apart; its tolerance chosen from ``DIFFRAX_TOLS`` as the loosest whose final-state error
  is at most rodjit's (matched accuracy).
- Accuracy, on ``SAMPLE`` points spread over the grid: against a CPU reference at rtol
  1e-11, atol 1e-14 (``energy``): the final state's max error (rodjit CPU at default
  tolerances; diffrax), and the GPU engine's summary columns against the CPU path's
  (the same algorithm: agreement to rounding expected).

Without a GPU it refuses in one line (exit 2).  ``--smoke`` runs every part at 2^2 points
in numba-cuda's simulator (NUMBA_ENABLE_CUDASIM=1): a check that the script works, not a
measurement (its numbers are not written).

    python benchmarks/bench_gpu.py                 # 2^10 .. 2^20, ~10 min on an H100
    python benchmarks/bench_gpu.py --max-exp 16    # shorter
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _util  # noqa: E402
import jax_rod  # noqa: E402

import rodjit  # noqa: E402
from rodjit.config import Config  # noqa: E402
from rodjit.sweeps.grid import Grid  # noqa: E402

SAMPLE = 16          # points of the accuracy comparison
DIFFRAX_TOLS = jax_rod.TOLS
COMPARED = ("restitution_first", "contact_time_first", "min_u0", "max_floor_force",
            "min_strain", "energy_error", "steps", "rejected_steps", "t_final", "n_bounces")


def grid_of(n: int) -> Grid:
    return Grid.from_spec({"rod.mu": f"linspace(0, 100, {n // 2})",
                           "floor.kappa_b": [1000.0, 3000.0]})


def base(integrator: str, t_end: float) -> Config:
    return Config().override({"time.t_end": t_end, "time.integrator": integrator})


def sample_indices(n: int) -> list[int]:
    return sorted(set(np.linspace(0, n - 1, min(SAMPLE, n)).astype(int).tolist()))


def gpu_runs(integrator, t_end, exps):
    from rodjit.gpu.engine import run_batch

    rows = []
    compile_s = None
    for k in exps:
        n = 2 ** k
        g = grid_of(n)
        b = base(integrator, t_end)
        configs = [g.config(b, i) for i in range(n)]
        res = run_batch(configs, np.arange(n))
        w = res.worker
        if compile_s is None:
            compile_s = w["compile_time"]
        done = int((res.values["status"] == "completed").sum())
        rows.append({"points": n, "completed": done, "kernel_s": w["kernel_time"],
                     "setup_s": w["setup_time"], "wall_s": w["wall_time"],
                     "traj_per_s_kernel": n / w["kernel_time"],
                     "traj_per_s_end_to_end": n / (w["wall_time"] - w["compile_time"])})
        print(f"  gpu {integrator} 2^{k}: {rows[-1]['traj_per_s_kernel']:.3g} traj/s "
              f"(kernel), {rows[-1]['traj_per_s_end_to_end']:.3g} end to end", flush=True)
    return rows, compile_s, res


def agreement(res, integrator, t_end, n):
    """Largest relative difference of the GPU's summary columns from the CPU path's, on the
    sample points of the last grid."""
    from rodjit.sweeps.point import PointTask, run_point

    g = grid_of(n)
    b = base(integrator, t_end)
    worst = {}
    for i in sample_indices(n):
        cpu = run_point(PointTask(i, g.config(b, i), None, ())).values
        for name in COMPARED:
            x, y = float(res.values[name][i]), float(cpu[name])
            if math.isnan(x) and math.isnan(y) or x == y:
                d = 0.0
            else:
                d = abs(x - y) / max(abs(y), 1e-300)
            worst[name] = max(worst.get(name, 0.0), d)
    return worst


def reference_states(t_end, n):
    """u(T) of the sample points at tight tolerance (by index), their configs, and rodjit's
    error at default tolerances."""
    g = grid_of(n)
    idx = sample_indices(n)
    configs = [g.config(base("energy", t_end), i) for i in idx]
    states, err = jax_rod.reference_states(configs)
    return {i: (u, c) for i, u, c in zip(idx, states, configs)}, err


def cpu_sweep(integrator, t_end, n):
    g = {"rod.mu": f"linspace(0, 100, {n // 2})", "floor.kappa_b": [1000.0, 3000.0]}
    t = time.perf_counter()
    table = rodjit.sweep(base(integrator, t_end), g, progress=False)
    wall = time.perf_counter() - t
    return {"points": n, "wall_s": wall, "traj_per_s": n / wall, "jobs": table.stats["jobs"]}


def diffrax_runs(t_end, exps, ref, target_err):
    """diffrax Tsit5 jit(vmap) (benchmarks/jax_rod.py) at the loosest tolerance that matches
    rodjit's accuracy."""
    reason = jax_rod.missing()
    if reason:
        return {"skipped": reason}
    c0 = base("energy", t_end)
    reason = jax_rod.unsupported(c0)
    if reason:
        return {"skipped": reason}
    solve = jax_rod.make_solver(c0)
    idx = sorted(ref)
    chosen, err = jax_rod.matched_tolerance(solve, [ref[i][1] for i in idx],
                                            [ref[i][0] for i in idx], target_err,
                                            DIFFRAX_TOLS)
    rows = []
    for k in exps:
        n = 2 ** k
        gr = grid_of(n)
        args = jax_rod.point_arrays([gr.config(c0, i) for i in range(n)])
        t = time.perf_counter()
        solve(*args, chosen).block_until_ready()       # compile (per shape) and run
        first = time.perf_counter() - t
        t = time.perf_counter()
        solve(*args, chosen).block_until_ready()
        wall = time.perf_counter() - t
        rows.append({"points": n, "wall_s": wall, "compile_and_run_s": first,
                     "traj_per_s": n / wall})
        print(f"  diffrax 2^{k}: {n / wall:.3g} traj/s", flush=True)
    return {"rtol": chosen, "final_state_error": err, "rows": rows}


def host_setup(n: int = 10_000) -> dict:
    """Points/s of the host's set-up of ``n`` points of the paper grid: the engine's batch
    set-up and one ``Run`` per point, in this run (each the best of 3, from no kept
    pieces)."""
    from rodjit.driver.run import Run
    from rodjit.driver.setup import clear, starts

    grid = grid_of(n)
    cfg = base("energy", 5.0)
    configs = [grid.config(cfg, i) for i in range(len(grid))]

    def best(fn):
        times = []
        for _ in range(3):
            clear()
            t0 = time.perf_counter()
            fn()
            times.append(time.perf_counter() - t0)
        return len(configs) / min(times)

    batch = best(lambda: starts(configs))
    per_point = best(lambda: [Run(c, snapshot_capacity=1, diag_capacity=1, event_capacity=1)
                              for c in configs])
    return {"points": len(configs), "batch_points_per_s": batch,
            "run_per_point_points_per_s": per_point}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--min-exp", type=int, default=10)
    ap.add_argument("--max-exp", type=int, default=20)
    ap.add_argument("--t-end", type=float, default=5.0)
    ap.add_argument("--integrators", default="energy,dp54")
    ap.add_argument("--smoke", action="store_true",
                    help="2^2 points in the simulator: checks the script, measures nothing")
    args = ap.parse_args()
    from rodjit.config import ModelWarning

    warnings.simplefilter("ignore", ModelWarning)     # the grid's μ = 0 column says it
    if args.smoke:
        os.environ["NUMBA_ENABLE_CUDASIM"] = "1"
        args.min_exp = args.max_exp = 2
        args.t_end = min(args.t_end, 0.3)
    from rodjit.gpu._cuda import CudaUnavailable
    from rodjit.gpu.engine import check_device
    from rodjit.gpu.kernel import simulated

    try:
        check_device()
    except CudaUnavailable as exc:
        print(f"bench_gpu: {exc}", file=sys.stderr)
        return 2
    if simulated() and not args.smoke:
        print("bench_gpu: NUMBA_ENABLE_CUDASIM=1 is set: the simulator's times measure "
              "nothing (use --smoke to check the script)", file=sys.stderr)
        return 2
    exps = list(range(args.min_exp, args.max_exp + 1))
    _util.header("GPU engine, paper grid (N = 5, mu in [0, 100] x kappa_b in {1000, 3000})")
    out = {"t_end": args.t_end, "grid": "rod.mu linspace(0, 100, n/2) x floor.kappa_b "
                                        "{1000, 3000}", "gpu": {}}
    out["host_setup"] = h = host_setup()
    print(f"  host set-up of {h['points']} points: {h['batch_points_per_s']:.3g} points/s "
          f"(batch, driver.setup) against {h['run_per_point_points_per_s']:.3g} points/s (one "
          f"Run per point)")
    for integ in args.integrators.split(","):
        rows, compile_s, last = gpu_runs(integ, args.t_end, exps)
        out["gpu"][integ] = {"compile_s": compile_s, "rows": rows,
                             "device": last.worker.get("device"),
                             "agreement_with_cpu": agreement(last, integ, args.t_end,
                                                             2 ** exps[-1])}
        print(_util.table([[r["points"], r["traj_per_s_kernel"], r["traj_per_s_end_to_end"],
                            r["kernel_s"], r["setup_s"]] for r in rows],
                          ["points", "traj/s kernel", "traj/s end-to-end", "kernel s",
                           "set-up s"]))
        print(f"  compile {compile_s:.3g} s; largest relative difference from the CPU "
              f"path: {max(out['gpu'][integ]['agreement_with_cpu'].values()):.3g}")
    cpu_n = 2 ** min(10, exps[-1])
    out["cpu"] = {integ: cpu_sweep(integ, args.t_end, cpu_n)
                  for integ in args.integrators.split(",")}
    for integ, r in out["cpu"].items():
        print(f"  cpu {integ} ({r['jobs']} jobs, {r['points']} points): "
              f"{r['traj_per_s']:.3g} traj/s")
    ref, rodjit_err = reference_states(args.t_end, 2 ** exps[-1])
    out["rodjit_final_state_error"] = rodjit_err
    print(f"  rodjit (energy, default tolerances) final-state error: {rodjit_err:.3g}")
    try:
        out["diffrax"] = diffrax_runs(args.t_end, [k for k in exps if k <= 17], ref,
                                      rodjit_err)
    except Exception as exc:        # the peer's failure must not lose the GPU's numbers
        out["diffrax"] = {"failed": f"{type(exc).__name__}: {exc}"}
    print(f"  diffrax: {out['diffrax'].get('skipped') or out['diffrax'].get('failed') or ''}")
    if args.smoke:
        print("bench_gpu: smoke run in the simulator: nothing written")
        return 0
    print(f"wrote {_util.save('bench_gpu', out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
