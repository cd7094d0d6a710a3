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
  batch set-up the engine uses (``rodjit.gpu.starts.starts``) against one ``Run`` per point
  (``start_of``, the set-up it replaced), the points' ``Config`` made beforehand.
- CPU path: ``rodjit.sweep`` on every core (the process pool), 2^10 points.
- diffrax 0.7 (if importable): Tsit5 with a PID controller, ``jax.jit(jax.vmap(...))`` over
  (μ, κ_b), on the semi-discrete system of MODEL.md §2 written in JAX here (γ = 0), compile
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

import rodjit  # noqa: E402
from rodjit.config import Config  # noqa: E402
from rodjit.sweeps.grid import Grid  # noqa: E402

SAMPLE = 16          # points of the accuracy comparison
DIFFRAX_TOLS = (1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
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
    """u(T), v(T) of the sample points at tight tolerance, and rodjit's error at default."""
    g = grid_of(n)
    ref, err = {}, 0.0
    for i in sample_indices(n):
        c = g.config(base("energy", t_end), i)
        tight = rodjit.simulate(c.override({"time.rtol": 1e-11, "time.atol": 1e-14}))
        dflt = rodjit.simulate(c)
        ref[i] = (np.asarray(tight.u_final), np.asarray(tight.v_final), c)
        err = max(err, float(np.max(np.abs(np.asarray(dflt.u_final) - ref[i][0]))))
    return ref, err


def cpu_sweep(integrator, t_end, n):
    g = {"rod.mu": f"linspace(0, 100, {n // 2})", "floor.kappa_b": [1000.0, 3000.0]}
    t = time.perf_counter()
    table = rodjit.sweep(base(integrator, t_end), g, progress=False)
    wall = time.perf_counter() - t
    return {"points": n, "wall_s": wall, "traj_per_s": n / wall, "jobs": table.stats["jobs"]}


def diffrax_runs(t_end, exps, ref, target_err):
    """diffrax Tsit5 jit(vmap) at the loosest tolerance that matches rodjit's accuracy."""
    try:
        import diffrax
        import jax
        import jax.numpy as jnp
    except ImportError as exc:
        return {"skipped": f"jax/diffrax not installed ({exc})"}
    jax.config.update("jax_enable_x64", True)
    c0 = base("energy", t_end)
    n_seg, kappa, beta, g = c0.rod.N, c0.rod.kappa, c0.floor.beta, c0.gravity.g
    if c0.rod.gamma != 0.0:
        return {"skipped": "the JAX right-hand side here has gamma = 0 only"}
    h = 1.0 / n_seg
    m = jnp.full(n_seg + 1, h).at[0].set(h / 2).at[-1].set(h / 2)

    def rhs(t, y, args):       # MODEL.md §2, γ = 0, Aiki–Kosugi laws
        mu, kb = args
        u, v = y[: n_seg + 1], y[n_seg + 1:]
        e = (u[1:] - u[:-1]) / h - 1.0
        q = 1.0 + e
        seg = 0.5 * kappa * (e + 0.5 - 0.5 / q**3) + mu * (v[1:] - v[:-1]) / h
        f = jnp.zeros(n_seg + 1).at[:-1].add(seg).at[1:].add(-seg) + m * g
        sb = jnp.where(u[0] <= 0.0, kb * (beta**3 / (u[0] + beta) ** 3 - 1.0), 0.0)
        f = f.at[0].add(sb)
        return jnp.concatenate([v, f / m])

    u0 = np.asarray(rodjit.simulate(c0.override({"time.t_end": 1e-9})).u[0])
    v0 = np.full(n_seg + 1, float(c0.initial.velocity))
    y0 = jnp.concatenate([jnp.asarray(u0), jnp.asarray(v0)])

    def make(tol):
        def one(mu, kb):
            sol = diffrax.diffeqsolve(
                diffrax.ODETerm(rhs), diffrax.Tsit5(), t0=0.0, t1=t_end, dt0=1e-5, y0=y0,
                args=(mu, kb), saveat=diffrax.SaveAt(t1=True), max_steps=10_000_000,
                stepsize_controller=diffrax.PIDController(rtol=tol, atol=tol * 1e-3))
            return sol.ys[-1]
        return jax.jit(jax.vmap(one))

    idx = sorted(ref)
    mus = jnp.asarray([ref[i][2].rod.mu for i in idx])
    kbs = jnp.asarray([ref[i][2].floor.kappa_b for i in idx])
    chosen, err = None, math.inf
    for tol in DIFFRAX_TOLS:
        ys = np.asarray(make(tol)(mus, kbs))
        err = max(float(np.max(np.abs(ys[q, : n_seg + 1] - ref[i][0])))
                  for q, i in enumerate(idx))
        if err <= target_err:
            chosen = tol
            break
    if chosen is None:
        chosen = DIFFRAX_TOLS[-1]
    solve = make(chosen)
    rows = []
    for k in exps:
        n = 2 ** k
        gr = grid_of(n)
        cs = [gr.config(c0, i) for i in range(n)]
        mu = jnp.asarray([c.rod.mu for c in cs])
        kb = jnp.asarray([c.floor.kappa_b for c in cs])
        t = time.perf_counter()
        solve(mu, kb).block_until_ready()       # compile (per shape) and run
        first = time.perf_counter() - t
        t = time.perf_counter()
        solve(mu, kb).block_until_ready()
        wall = time.perf_counter() - t
        rows.append({"points": n, "wall_s": wall, "compile_and_run_s": first,
                     "traj_per_s": n / wall})
        print(f"  diffrax 2^{k}: {n / wall:.3g} traj/s", flush=True)
    return {"rtol": chosen, "final_state_error": err, "rows": rows}


def host_setup(n: int = 10_000) -> dict:
    """Points/s of the host's set-up of ``n`` points of the paper grid: the engine's batch
    set-up and one ``Run`` per point, in this run (each the best of 3)."""
    from rodjit.gpu.starts import start_of, starts

    grid = grid_of(n)
    cfg = base("energy", 5.0)
    configs = [grid.config(cfg, i) for i in range(len(grid))]

    def best(fn):
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            fn()
            times.append(time.perf_counter() - t0)
        return len(configs) / min(times)

    batch = best(lambda: starts(configs))
    per_point = best(lambda: [start_of(c) for c in configs])
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
          f"(batch, gpu.starts) against {h['run_per_point_points_per_s']:.3g} points/s (one "
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
