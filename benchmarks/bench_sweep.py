"""Parameter sweeps: scaling over two cores, Dask against the process pool, the
overhead per point, and the sweep against its CPU time and CyRK's process pool.

1. A 64-point grid over μ × κ_b × β (4 × 4 × 4) on the paper setting (data/paper_mu100.toml:
   N = 5, semi-implicit, t_end = 5 s): points per second with 1 and with 2 worker processes.
   Target: ≥ 1.8× with 2 jobs on 2 cores.
2. The same grid on a Dask LocalCluster of 2 single-threaded worker processes against the
   pool with 2 jobs: target overhead < 15 %.  For context, also 1 worker against 1 job,
   where a core is left for the scheduler, nannies and client, which run in this process.
3. Small rods where the overhead dominates: 256 points (N = 5, t_end = 0.02 s, ~60 steps
   each), 1 job.  Overhead per point = (sweep time − start-up) × jobs / points − the point's
   own stepping time (``run_time``): dispatch, the point's set-up in its worker, the result's
   trip back and its HDF5 row.  Target < 20 ms.
4. The 2000-point grid μ (200 values in [0, 100]) × κ_b ∈ {1000, 3000} × β (5 values) on
   paper-mu100 with 2 jobs (``--grid-points`` scales μ): the sweep's wall time against the
   compiled stepping of its points (the sum of their ``run_time`` over the jobs, the lower
   bound of any sweep engine calling the same loop); target within 1.3x.  The HDF5 objects
   of its file (target at most 300).  With ``--baseline CHECKOUT`` the same sweep is run
   by the rodjit of another checkout (``rodjit sweep`` in a child process with that tree
   first on ``sys.path``), in turns with this one, and the ratio of the two is printed.

5. ``--engine`` (only this part): the grid of part 4 at 2000 and 20000 points (μ over 200
   and 2000 values) on 2 jobs: points/s of the ensemble engine (batches of points in one
   compiled call, the default), of the per-point path (``run_sweep.ENGINE = False``: every
   point through ``point.run_point``, a ``Run`` each) and of the stepping-only lower bound
   (the sum of the per-point path's ``run_time``, each point's loop run alone, over the 2
   jobs), and the engine's wall time over that bound and over its own compiled calls.  The
   per-point path of the 20000 points runs only with ``--full`` (its bound is then the
   2000-point one scaled by the points).  First, in this process and in turns (so that the
   load of a shared machine hits both alike): 80 points as one batch against the same
   points through the per-point path and their loops' own ``run_time``.
   With ``--baseline CHECKOUT`` also the 2000-point sweep by this tree's and that tree's
   ``rodjit sweep`` (child processes, in turns, ``--repeat`` pairs): the speed-up, the two
   sweeps' total steps, and the speed-up per step (the target's allowance for points that
   now take more steps).  A CHECKOUT without a usable ahead-of-time extension gets it
   compiled first (``ahead_of_time``), as its install would.  Then the compiled loop's cost
   per step in both trees on 16 of the grid's points, the two at once on the two cores
   (``loop_pairs``), which says how much of the per-step speed-up the loop itself holds
   or gives back.  With ``--memory`` the 20000-point sweep once more through the
   command line, its process tree's resident memory summed every 20 ms: the peak.
   The diffrax row (when jax and diffrax import; ``--diffrax`` runs only it): diffrax Tsit5
   ``jax.jit(jax.vmap(...))`` on the CPU over (μ, κ_b, β) of the 2000-point grid
   (benchmarks/jax_rod.py: MODEL.md §2 in JAX, γ = 0, refused in one line for a base it
   cannot represent), at the loosest tolerance whose final-state error on DIFFRAX_SAMPLE
   random points is at most rodjit's (both against rodjit at rtol 1e-11, atol 1e-14);
   timed on DIFFRAX_POINTS points drawn at random from the 2000 (``--diffrax-points``; 0
   for all of them), compile apart (the first call of a shape, minus a second), in turns
   with the same points as one ensemble batch in this process (one core each).

6. ``--peer`` (only this part): ``rodjit sweep paper-mu100 --grid
   "rod.mu=linspace(100,300,P)" --jobs 2 -q -o F``, the command a user types, in a child
   process, for P = 20, 200 and 2000: its wall time against the CPU time of all its
   processes (the command, its fork server and workers) over the jobs plus one start-up,
   the wall of the same command over 2 points; target ≤ 1.3.  The CPU time is
   ``RUSAGE_CHILDREN`` before and after, this process made the reaper of the command's
   orphans (``adopt_orphans``: the fork server and its workers outlive the command and
   nobody else waits for them), checked against the tree's CPU time read from ``/proc``
   every 50 ms.  The marginal ratio (wall − the 2-point wall) / ((CPU − its CPU) / jobs)
   says how much of the rest the start-up explains.  CPU time does not see what other load
   on a shared machine takes from the workers, the wall does: beside it the wall over the
   points' loops (their ``run_time``, wall time in which a worker never waits on the
   sweep) over the jobs plus the start-up, which that load hits as it hits the wall.  Then the 200-point grid against
   CyRK (``bench_peers``: the same right-hand side ``peer_rhs``, its runner ``run_cyrk``)
   at matched accuracy: the state error over the first second as ``bench_peers`` measures
   it (snapshots every 5 ms, against CyRK DOP853 at rtol = atol = 1e-13) on PEER_SAMPLE
   points spread over the grid; rodjit's at the preset's settings (its configuration with
   t_end = 1 s, snapshots every 5 ms as it has them: the sweep's steps over that second,
   landing on the same output times), the peer's the loosest rtol = atol of a
   half-decade ladder 1e-3 … 1e-10 whose largest error is at most rodjit's, for CyRK
   Radau and DOP853.  Each then solves the 200 points over the preset's t_end (output
   every 1 ms, the sweep's diagnostics interval; each point's final state returned) in a
   spawned ``multiprocessing`` Pool(2), whose workers compile the cfunc and the solver in
   their initializer (timed and printed apart, not in the pool's time), in turns with the
   sweeps above: rodjit's speed over the fastest pool's, rodjit's wall as the user meets
   it (start-up included) and without the start-up; target ≥ 0.67.  Also against the
   points' loops alone, and with the pool's own start-up (spawn, imports, compiles) added.  For context, the same
   200-point sweep with ``--set time.integrator=radau5`` (the preset's tolerances) and its
   error.

Each sweep writes its sweep file like ``rodjit sweep -o``.  A sweep's time is split into
start-up (the workers importing rodjit and loading the kernels, until all report ready; a
LocalCluster's scheduler and workers), the steady state until the last result, which is what
points per second measure, and the teardown (stopping the workers or the cluster); the
end-to-end ratios are printed too.  Each configuration is timed --repeat times in turns
(best kept), so the machine's load hits every one alike.

    python benchmarks/bench_sweep.py [--repeat 3] [--quick] [--baseline CHECKOUT]
    python benchmarks/bench_sweep.py --engine [--full] [--baseline CHECKOUT] [--memory]
    python benchmarks/bench_sweep.py --diffrax [--diffrax-points 200]
    python benchmarks/bench_sweep.py --peer [--repeat 3]
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _util  # noqa: E402
import jax_rod  # noqa: E402

import rodjit  # noqa: E402
from rodjit.presets import load_preset  # noqa: E402

GRID = {"rod.mu": [0.0, 1.0, 10.0, 100.0], "floor.kappa_b": "logspace(3, 5, 4)",
        "floor.beta": [0.01, 0.02, 0.03, 0.05]}
SMALL_GRID = {"rod.mu": "linspace(0, 10, 16)", "floor.beta": "linspace(0.01, 0.05, 16)"}
TARGET_SCALING, TARGET_DASK, TARGET_OVERHEAD = 1.8, 0.15, 0.020
TARGET_STEPPING, TARGET_OBJECTS = 1.3, 300
DIFFRAX_SAMPLE = 8          # points of part 5's grid where diffrax's tolerance is matched
DIFFRAX_POINTS = 200        # the points diffrax is timed on (of the 2000; 0: all)


def big_grid(mu_values: int) -> dict:
    """The grid of part 4: μ over ``mu_values`` values × 2 κ_b × 5 β."""
    return {"rod.mu": f"linspace(0, 100, {mu_values})", "floor.kappa_b": [1000.0, 3000.0],
            "floor.beta": [0.03, 0.05, 0.08, 0.1, 0.12]}


def _sweep_command(tree: str, grid: dict, out: Path, jobs: int) -> tuple[list, dict]:
    """``rodjit sweep paper-mu100`` over ``grid`` by the rodjit of the checkout ``tree``:
    its arguments and environment."""
    args = [sys.executable, "-m", "rodjit", "sweep", "paper-mu100", "-o", str(out),
            "--overwrite", "--jobs", str(jobs), "-q"]
    for key, values in grid.items():
        text = values if isinstance(values, str) else ",".join(repr(v) for v in values)
        args += ["--grid", f"{key}={text}"]
    return args, dict(os.environ, PYTHONPATH=str(Path(tree).resolve()))


_AHEAD = """
import sys
from rodjit.stepping import aot
if aot._extension()[0] is None and hasattr(aot, "build"):
    from rodjit.config import Config
    from rodjit.driver.run import Run
    from pathlib import Path
    if hasattr(aot, "schemes"):      # entries per scheme it names (setup.py); older: one set
        from rodjit.driver.setup import parameters
        aot.build(Path(aot.__file__).parent, [parameters(Config().override(
            {"time.integrator": name})) for name in aot.schemes()])
    else:
        aot.build(Path(aot.__file__).parent, Run(Config())._args())
    print("built")
"""


def ahead_of_time(tree: str) -> None:
    """Compile the checkout ``tree``'s ahead-of-time extension where it lacks a usable one,
    as its install would (a baseline on the JIT would pay Numba's start-up in every worker,
    which its users do not)."""
    env = dict(os.environ, PYTHONPATH=str(Path(tree).resolve()))
    # run in the checkout: ``python -c`` looks in the working directory first
    done = subprocess.run([sys.executable, "-c", _AHEAD], env=env, cwd=tree,
                          capture_output=True, text=True)
    if done.returncode != 0:
        print(f"   {tree}: no ahead-of-time extension ({done.stderr.strip().splitlines()[-1]})"
              f"; it runs on the JIT")
    elif "built" in done.stdout:
        print(f"   {tree}: its ahead-of-time extension compiled, as its install would")


def cli_sweep(tree: str, grid: dict, out: Path, jobs: int) -> float:
    """Wall time of ``rodjit sweep paper-mu100`` over ``grid`` run by the rodjit of the
    checkout ``tree`` in a child process."""
    args, env = _sweep_command(tree, grid, out, jobs)
    t0 = time.perf_counter()
    subprocess.run(args, env=env, check=True, cwd=out.parent, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t0


def proc_table() -> dict[int, tuple[int, float, int]]:
    """Every process of the machine (Linux ``/proc``): pid -> (parent pid, CPU seconds
    used so far, user and system, resident bytes)."""
    tick, page = os.sysconf("SC_CLK_TCK"), os.sysconf("SC_PAGE_SIZE")
    table = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        # after the command: state, ppid, ..., utime and stime (fields 14, 15 of stat,
        # indices 11, 12 here), ..., rss in pages (field 24, index 21)
        table[int(entry)] = (int(fields[1]), (int(fields[11]) + int(fields[12])) / tick,
                             int(fields[21]) * page)
    return table


def descendants(pid: int, table: dict) -> set[int]:
    """``pid`` and every process below it in ``table`` (``proc_table``'s form)."""
    children: dict[int, list[int]] = {}
    for p, row in table.items():
        children.setdefault(row[0], []).append(p)
    out, todo = set(), [pid]
    while todo:
        p = todo.pop()
        out.add(p)
        todo += children.get(p, [])
    return out


def tree_rss(pid: int) -> int:
    """Resident bytes of process ``pid`` and all its descendants (Linux ``/proc``)."""
    table = proc_table()
    return sum(table[p][2] for p in descendants(pid, table) if p in table)


def peak_memory(tree: str, grid: dict, out: Path, jobs: int) -> dict:
    """The peak resident memory of ``rodjit sweep`` over ``grid`` (its process and its
    workers together, sampled every 20 ms) and its wall time."""
    args, env = _sweep_command(tree, grid, out, jobs)
    t0 = time.perf_counter()
    proc = subprocess.Popen(args, env=env, cwd=out.parent, stdout=subprocess.DEVNULL)
    peak = 0
    while proc.poll() is None:
        peak = max(peak, tree_rss(proc.pid))
        time.sleep(0.02)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"the sweep for the memory peak exited {proc.returncode}")
    return {"peak_bytes": peak, "wall": wall, "points": len(rodjit.load_sweep(out))}


def total_steps(path: Path) -> int:
    table = rodjit.load_sweep(path)
    return int(np.sum(table["steps"]))


def baseline_part(tree: str, baseline: str, tmp, repeat: int) -> dict:
    """The 2000-point sweep by this tree's and ``baseline``'s command line, in turns."""
    grid = big_grid(200)
    here_walls, base_walls = [], []
    ahead_of_time(baseline)
    cli_sweep(baseline, {"rod.mu": [0.0]}, Path(tmp) / "warm.h5", 1)   # its kernels cached
    for _ in range(repeat):
        here_walls.append(cli_sweep(tree, grid, Path(tmp) / "cli_here.h5", 2))
        base_walls.append(cli_sweep(baseline, grid, Path(tmp) / "cli_base.h5", 2))
    steps_here = total_steps(Path(tmp) / "cli_here.h5")
    steps_base = total_steps(Path(tmp) / "cli_base.h5")
    ratio = float(np.median(np.array(base_walls) / np.array(here_walls)))
    per_step = ratio * steps_here / steps_base
    print(f"   2000 points by {baseline}: {min(base_walls):.2f} s, by this tree "
          f"{min(here_walls):.2f} s (CLI end to end, best of {repeat}): {ratio:.2f}x faster "
          f"(median of pairs); steps {steps_base} there, {steps_here} here "
          f"({steps_here / steps_base:.2f}x): {per_step:.2f}x faster per step (target >= 4x)")
    return {"baseline": baseline, "baseline_wall": min(base_walls), "wall": min(here_walls),
            "speedup": ratio, "steps_baseline": steps_base, "steps": steps_here,
            "speedup_per_step": per_step}


# the grid points whose loops ``loop_pairs`` times: μ × κ_b × β of part 4's grid without
# μ = 0 (its chattering points take twenty times the steps and are 1 in 200 of the grid)
LOOP_POINTS = tuple((mu, kb, beta) for mu in (10.0, 40.0, 70.0, 100.0)
                    for kb in (1000.0, 3000.0) for beta in (0.05, 0.1))

# a child of ``loop_pairs``: pinned to one core, the compiled loop's best ``run_time`` per
# point over ``reps`` calls (after a warm-up call each), per step taken
_LOOP = """
import json, os, sys, warnings
warnings.simplefilter("ignore")
cpu, reps, t_end, points = json.loads(sys.argv[1])
if cpu is not None:
    os.sched_setaffinity(0, {cpu})
import rodjit
from rodjit.presets import load_preset
base = load_preset("paper-mu100")
if t_end is not None:
    base = base.override({"time.t_end": t_end})
configs = [base.override({"rod.mu": m, "floor.kappa_b": k, "floor.beta": b})
           for m, k, b in points]
for c in configs:
    rodjit.simulate(c)
best = [float("inf")] * len(configs)
steps = [0] * len(configs)
for _ in range(reps):
    for j, c in enumerate(configs):
        r = rodjit.simulate(c)
        best[j] = min(best[j], r.stats["run_time"])
        steps[j] = int(r.stats["steps"])
print(json.dumps({"run_time": sum(best), "steps": sum(steps)}))
"""


def loop_pairs(here: str, baseline: str, rounds: int, points=LOOP_POINTS, reps: int = 9,
               t_end: float | None = None) -> dict:
    """The compiled loop's cost per step in this tree and in ``baseline``, on the same grid
    points (``LOOP_POINTS``, best of ``reps`` calls each): what is left when the sweep
    around the loop costs nothing.  The two trees run at the same time, each pinned to one
    of two cores and swapped every round, so that the shared machine's drift, which moves
    its speed by 10 % to 2× from one minute to the next, hits both alike (one after the
    other, it decides the ratio); on one core they run in turns.  Returns both trees' ns
    per step per round and the median of the rounds' ratios (baseline / here)."""
    cores = sorted(os.sched_getaffinity(0))[:2] if hasattr(os, "sched_getaffinity") else []
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1",
               NUMBA_NUM_THREADS="1")

    def start(tree, cpu):
        arg = json.dumps([cpu, reps, t_end, [list(p) for p in points]])
        return subprocess.Popen([sys.executable, "-c", _LOOP, arg], cwd=tree,
                                env=dict(env, PYTHONPATH=str(Path(tree).resolve())),
                                stdout=subprocess.PIPE, text=True)

    def finish(*procs):
        outs = [p.communicate()[0] for p in procs]     # both waited for, even if one failed
        for p in procs:
            if p.returncode != 0:
                raise SystemExit(f"a loop timing child exited {p.returncode}")
        rs = [json.loads(out.strip().splitlines()[-1]) for out in outs]
        return [(1e9 * r["run_time"] / r["steps"], r["steps"]) for r in rs]

    here_ns, base_ns = [], []
    for k in range(rounds):
        if len(cores) == 2:
            (ha, steps_here), (hb, steps_base) = finish(start(here, cores[k % 2]),
                                                        start(baseline, cores[1 - k % 2]))
        else:
            (ha, steps_here), = finish(start(here, None))
            (hb, steps_base), = finish(start(baseline, None))
        here_ns.append(ha)
        base_ns.append(hb)
    ratio = float(np.median(np.array(base_ns) / np.array(here_ns)))
    how = ("both trees at once, one core each, swapped every round" if len(cores) == 2
           else "in turns")
    print(f"   the compiled loop per step on {len(points)} grid points (best of {reps} calls "
          f"each; {how}, {rounds} rounds): here {np.median(here_ns):.0f} ns, {baseline} "
          f"{np.median(base_ns):.0f} ns: {ratio:.2f}x (baseline / here, median of rounds)")
    return {"points": [list(p) for p in points], "reps": reps, "here_ns": here_ns,
            "baseline_ns": base_ns, "steps_here": steps_here, "steps_baseline": steps_base,
            "ratio": ratio}


def objects(path) -> int:
    names: list[str] = []
    with h5py.File(path, "r") as f:
        f.visit(names.append)
    return len(names)


def stepping_bound(base, grid: dict, tmp, repeat: int, baseline: str | None) -> dict:
    """Part 4: the grid's sweep on 2 jobs against the compiled stepping of its points."""
    jobs = 2
    here = str(Path(__file__).resolve().parents[1])
    runs, ratios, base_walls = [], [], []
    if baseline is not None:
        ahead_of_time(baseline)
    for _ in range(repeat):
        r = timed_sweep(base, grid, tmp, jobs=jobs)
        table = rodjit.load_sweep(Path(tmp) / "bench_sweep.h5")
        r["stepping"] = float(np.sum(table["run_time"])) / jobs
        r["objects"] = objects(Path(tmp) / "bench_sweep.h5")
        runs.append(r)
        if baseline is not None:   # in turns with the same sweep by both trees' CLI
            a = cli_sweep(here, grid, Path(tmp) / "cli_here.h5", jobs)
            b = cli_sweep(baseline, grid, Path(tmp) / "cli_base.h5", jobs)
            ratios.append(b / a)
            base_walls.append(b)
    r = min(runs, key=lambda x: x["wall"])
    out = {"grid": grid, "jobs": jobs, "points": r["points"], "wall": r["wall"],
           "steady": r["steady"], "stepping": r["stepping"],
           "wall_over_stepping": r["wall"] / r["stepping"],
           "steady_over_stepping": r["steady"] / r["stepping"], "objects": r["objects"]}
    if ratios:
        out["baseline"] = baseline
        out["baseline_wall"] = min(base_walls)
        out["speedup_over_baseline"] = float(np.median(ratios))
    return out


def print_stepping_bound(b: dict) -> None:
    rows = [[b["points"], b["jobs"], b["wall"], b["steady"], b["stepping"],
             b["wall_over_stepping"], b["steady_over_stepping"], b["objects"]]]
    print(_util.table(rows, ["grid points", "jobs", "wall [s]", "steady [s]",
                             "stepping/jobs [s]", "wall/stepping", "steady/stepping",
                             "HDF5 objects"]))
    ok = b["wall_over_stepping"] <= TARGET_STEPPING
    print(f"   wall / compiled stepping: {b['wall_over_stepping']:.2f}x (target <= "
          f"{TARGET_STEPPING}x: {'yes' if ok else 'NO'}); HDF5 objects {b['objects']} "
          f"(target <= {TARGET_OBJECTS}: {'yes' if b['objects'] <= TARGET_OBJECTS else 'NO'})")
    if "speedup_over_baseline" in b:
        print(f"   the same sweep by {b['baseline']}: {b['baseline_wall']:.2f} s; this tree "
              f"is {b['speedup_over_baseline']:.2f}x faster (median of pairs, CLI end to end)")


def timed_sweep(base, grid, tmp, **kwargs) -> dict:
    path = Path(tmp) / "bench_sweep.h5"
    table = rodjit.sweep(base, grid, output=path, overwrite=True, **kwargs)
    s = table.stats
    n = len(table)
    steady = s["wall_time"] - (s["startup_time"] or 0.0) - s["teardown_time"]
    assert table.counts["completed"] == n, table.report()
    return {"wall": s["wall_time"], "startup": s["startup_time"] or 0.0, "steady": steady,
            "teardown": s["teardown_time"],
            "points": n, "jobs": s["jobs"], "backend": s["backend"],
            "points_per_second": n / steady, "points_per_second_end_to_end": n / s["wall_time"],
            "point_wall_mean": float(np.mean(table["wall_time"])),
            "point_run_mean": float(np.mean(table["run_time"])),
            "overhead_per_point": steady * s["jobs"] / n - float(np.mean(table["run_time"])),
            "setup_in_worker": float(np.mean(table["wall_time"] - table["run_time"]))}


def best_of(runs: list[dict]) -> dict:
    return min(runs, key=lambda r: r["steady"])


def in_process(base, repeat: int = 3) -> dict:
    """Part 5, in this process, in turns (the machine's load hits both alike): 80 points of
    the grid as one batch (``ensemble.run_batch``) against the same points through
    ``point.run_point``, and their loops' own ``run_time``."""
    from rodjit.sweeps.ensemble import BatchTask, run_batch
    from rodjit.sweeps.grid import Grid
    from rodjit.sweeps.point import PointTask, run_point

    grid = Grid.from_spec(big_grid(8))
    idx = np.arange(len(grid))
    run_batch(BatchTask(idx[:2], base, grid, ()))
    rows = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        run_batch(BatchTask(idx, base, grid, ()))
        t1 = time.perf_counter()
        points = [run_point(PointTask(int(i), grid.config(base, int(i)), None, ())) for i in idx]
        t2 = time.perf_counter()
        rows.append((t1 - t0, t2 - t1, sum(p.values["run_time"] for p in points)))
    batch, per_point, loops = (min(r[j] for r in rows) for j in range(3))
    print(f"   80 points in this process (best of {repeat}): one batch {batch:.3f} s, "
          f"per-point path {per_point:.3f} s, their loops' run_time {loops:.3f} s: batch / "
          f"loops {batch / loops:.2f}x, per-point / loops {per_point / loops:.2f}x")
    return {"points": int(idx.size), "batch": batch, "per_point": per_point, "loops": loops}


def threads_part(base, repeat: int = 3) -> dict:
    """Threads over batches against processes: 160 points of the grid as two batches of
    80 (alternate points), run one after the other in this process, then at once by two threads (the batch
    call releases the GIL), then at once by two worker processes, in turns.  A speed-up
    near 2 for the threads would let one process per machine serve a sweep; the processes
    are what the pool and Dask use."""
    from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

    from rodjit.sweeps.ensemble import BatchTask, run_batch
    from rodjit.sweeps.grid import Grid

    grid = Grid.from_spec(big_grid(16))
    idx = np.arange(len(grid))
    # every other point to each batch, so the two carry the same work (the grid's
    # μ = 0 points take the most steps)
    tasks = [BatchTask(idx[0::2], base, grid, ()), BatchTask(idx[1::2], base, grid, ())]
    run_batch(BatchTask(idx[:2], base, grid, ()))
    rows = []
    with ProcessPoolExecutor(2) as procs:
        list(procs.map(run_batch, [BatchTask(idx[:2], base, grid, ())] * 2))   # warm
        for _ in range(repeat):
            t0 = time.perf_counter()
            for t in tasks:
                run_batch(t)
            t1 = time.perf_counter()
            with ThreadPoolExecutor(2) as pool:
                list(pool.map(run_batch, tasks))
            t2 = time.perf_counter()
            list(procs.map(run_batch, tasks))
            t3 = time.perf_counter()
            rows.append((t1 - t0, t2 - t1, t3 - t2))
    one, threads, processes = (min(r[j] for r in rows) for j in range(3))
    print(f"   160 points as 2 batches of alternate points (best of {repeat}): one after the other {one:.3f} s, "
          f"2 threads {threads:.3f} s ({one / threads:.2f}x), 2 processes {processes:.3f} s "
          f"({one / processes:.2f}x)")
    return {"points": int(idx.size), "sequential": one, "threads": threads,
            "processes": processes}


def engine_part(base, tmp, full: bool) -> dict:
    """Part 5 (module docstring)."""
    from rodjit.sweeps import run_sweep

    out = {"in_process": in_process(base), "threads": threads_part(base)}
    for mu_values in (200, 2000):
        grid = big_grid(mu_values)
        eng = timed_sweep(base, grid, tmp, jobs=2)
        compiled = float(np.sum(rodjit.load_sweep(Path(tmp) / "bench_sweep.h5")["run_time"]))
        row = {"points": eng["points"], "engine_wall": eng["wall"],
               "engine_steady": eng["steady"], "engine_startup": eng["startup"],
               "engine_points_per_second": eng["points"] / eng["wall"],
               # the time of its batches' compiled calls over the 2 jobs (stepping and the
               # compiled observables): the engine's own Python outside them is the rest
               "engine_compiled": compiled / 2,
               "engine_wall_over_compiled": eng["wall"] / (compiled / 2)}
        if mu_values == 200 or full:
            run_sweep.ENGINE = False
            try:
                per = timed_sweep(base, grid, tmp, jobs=2)
            finally:
                run_sweep.ENGINE = True
            table = rodjit.load_sweep(Path(tmp) / "bench_sweep.h5")
            stepping = float(np.sum(table["run_time"])) / 2
            row.update(per_point_wall=per["wall"],
                       per_point_points_per_second=per["points"] / per["wall"])
        else:
            stepping = out[200]["stepping"] * mu_values / 200
        row.update(stepping=stepping, stepping_points_per_second=row["points"] / stepping,
                   engine_over_stepping=eng["wall"] / stepping)
        out[mu_values] = row
    rows = [[r["points"], r["engine_wall"], r["engine_startup"],
             r["engine_points_per_second"],
             r.get("per_point_points_per_second", float("nan")),
             r["stepping_points_per_second"], r["engine_over_stepping"],
             r["engine_wall_over_compiled"]]
            for k, r in out.items() if isinstance(k, int)]
    print(_util.table(rows, ["grid points (2 jobs)", "engine wall [s]", "start-up [s]",
                             "engine points/s", "per-point points/s",
                             "stepping-only points/s", "engine wall / stepping",
                             "engine wall / its compiled calls"]))
    return out


def diffrax_part(base, points: int, repeat: int = 2) -> dict:
    """Part 5's diffrax row (module docstring): points/s of diffrax ``jit(vmap)`` on the CPU
    at rodjit's accuracy, against the same points as one ensemble batch in this process."""
    from rodjit.sweeps.ensemble import BatchTask, run_batch
    from rodjit.sweeps.grid import Grid

    reason = jax_rod.missing() or jax_rod.unsupported(base)
    if reason:
        print(f"   diffrax row skipped: {reason}")
        return {"skipped": reason}
    grid = Grid.from_spec(big_grid(200))
    n = len(grid)
    rng = np.random.default_rng(0)
    sample = sorted(rng.choice(n, DIFFRAX_SAMPLE, replace=False).tolist())
    idx = np.arange(n) if not points or points >= n else np.sort(
        rng.choice(n, points, replace=False))
    configs = [grid.config(base, int(i)) for i in sample]
    ref, rodjit_err = jax_rod.reference_states(configs)
    solve = jax_rod.make_solver(base)
    t0 = time.perf_counter()
    tol, err = jax_rod.matched_tolerance(solve, configs, ref, rodjit_err)
    matching = time.perf_counter() - t0
    args = jax_rod.point_arrays([grid.config(base, int(i)) for i in idx])
    t0 = time.perf_counter()
    solve(*args, tol).block_until_ready()             # compiles for this shape, and runs
    first = time.perf_counter() - t0
    run_batch(BatchTask(idx[:2], base, grid, ()))     # the batch kernels loaded
    walls, batches = [], []
    for _ in range(repeat):                            # in turns: the load hits both alike
        t0 = time.perf_counter()
        solve(*args, tol).block_until_ready()
        walls.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        run_batch(BatchTask(idx, base, grid, ()))
        batches.append(time.perf_counter() - t0)
    wall, batch = min(walls), min(batches)
    out = {"points": int(idx.size), "of": n, "tol": tol, "atol": tol * 1e-3,
           "final_state_error": err, "rodjit_final_state_error": rodjit_err,
           "sample": sample, "wall": wall, "compile": first - wall,
           "tolerance_matching": matching, "points_per_second": idx.size / wall,
           "rodjit_batch_wall": batch, "rodjit_batch_points_per_second": idx.size / batch}
    subset = "" if idx.size == n else f" ({idx.size} of the {n} points, drawn at random)"
    print(f"   diffrax Tsit5 jit(vmap), CPU{subset}: rtol {tol:g}, atol {tol * 1e-3:g} "
          f"(final-state error {err:.2g} on {len(sample)} points, rodjit's {rodjit_err:.2g}); "
          f"{wall:.2f} s, {out['points_per_second']:.3g} points/s (best of {repeat}), "
          f"compile {out['compile']:.1f} s apart; the same points as one rodjit batch in "
          f"this process {batch:.2f} s, {out['rodjit_batch_points_per_second']:.3g} points/s "
          f"(rodjit / diffrax points/s: {wall / batch:.2f}x, one core each)")
    return out


# ---- part 6 (--peer): the sweep's wall against its CPU, and against CyRK's process pool --
PEER_POINTS = (20, 200, 2000)    # the grids whose wall is held against their CPU
PEER_TIMED = 200                 # the grid timed against CyRK's pool
PEER_JOBS = 2
PEER_SAMPLE = 8                  # grid points where the peer's tolerance is matched
PEER_TOLS = tuple(10.0 ** (-k / 2) for k in range(6, 21))     # 1e-3 … 1e-10, half decades
PEER_METHODS = ("Radau", "DOP853")
PEER_T_EVAL = 0.001              # the peer's output interval: the sweep's diagnostics_interval
TARGET_CPU, TARGET_PEER = 1.3, 0.67


def peer_grid(points: int) -> dict:
    """Part 6's grid: μ over ``points`` values in [100, 300] on paper-mu100."""
    return {"rod.mu": f"linspace(100, 300, {points})"}


def adopt_orphans() -> bool:
    """Make this process the reaper of its orphaned descendants (Linux
    ``PR_SET_CHILD_SUBREAPER``).  ``rodjit sweep``'s fork server and the workers forked from
    it are waited for by nobody once the command has exited: without this their CPU time
    never reaches ``RUSAGE_CHILDREN`` (``/usr/bin/time`` sees the sweep's own process only).
    False where the call is unavailable."""
    try:
        import ctypes
        return ctypes.CDLL(None, use_errno=True).prctl(36, 1, 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _children_cpu() -> float:
    import resource
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def cpu_run(args: list, env: dict | None = None, cwd=None, interval: float = 0.05,
            reap_wait: float = 60.0) -> dict:
    """Wall time of the command ``args`` in a child process and the CPU time of all its
    processes: ``RUSAGE_CHILDREN`` before and after, once every process it left behind
    (adopted by this one, ``adopt_orphans``) has been reaped.  ``cpu_sampled`` checks it:
    the CPU time of every process of the tree read from ``/proc`` every ``interval``
    seconds, each process's last reading summed (a lower bound: it misses each process's
    last ``interval``)."""
    me = os.getpid()
    own = descendants(me, proc_table())       # this process's own children (a pool's)
    c0 = _children_cpu()
    t0 = time.perf_counter()
    proc = subprocess.Popen(args, env=env, cwd=cwd, stdout=subprocess.DEVNULL)
    sampled: dict[int, float] = {}
    while proc.poll() is None:
        table = proc_table()
        for p in descendants(me, table) - own:
            if p in table:
                sampled[p] = table[p][1]
        time.sleep(interval)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(map(str, args[1:6]))} ... exited {proc.returncode}")
    deadline = time.perf_counter() + reap_wait
    while time.perf_counter() < deadline:
        left = [p for p, row in proc_table().items() if row[0] == me and p not in own]
        if not left:
            break
        for p in left:
            try:
                os.waitpid(p, os.WNOHANG)
            except ChildProcessError:
                pass
        time.sleep(0.01)
    else:
        print(f"   (processes left by the command still ran after {reap_wait:g} s: their "
              f"CPU time is not counted)")
    return {"wall": wall, "cpu": _children_cpu() - c0, "cpu_sampled": sum(sampled.values())}


def peer_sweep(points: int, out: Path, sets: tuple = ()) -> dict:
    """``rodjit sweep paper-mu100 --grid "rod.mu=linspace(100,300,P)" --jobs 2 -q -o out``
    as a user types it (``cpu_run``), with the sum of its points' ``run_time``."""
    here = str(Path(__file__).resolve().parents[1])
    args, env = _sweep_command(here, peer_grid(points), out, PEER_JOBS)
    for s in sets:
        args += ["--set", s]
    r = cpu_run(args, env, cwd=out.parent)
    table = rodjit.load_sweep(out)
    assert len(table) == points and table.counts["completed"] == points, table.report()
    r.update(points=points, stepping=float(np.sum(table["run_time"])),
             steps=int(np.sum(table["steps"])))
    return r


def peer_problems(base, mus) -> list:
    """The peer's problem of each μ over the preset's full t_end, output every
    PEER_T_EVAL: what ``bench_peers.run_cyrk`` takes (y0, the packed parameters, t_eval)."""
    from types import SimpleNamespace

    import peer_rhs
    from rodjit.model.system import initial_state
    u0, v0 = initial_state(base)
    y0 = np.concatenate([u0, v0])
    t_eval = PEER_T_EVAL * np.arange(int(round(base.time.t_end / PEER_T_EVAL)) + 1)
    return [SimpleNamespace(y0=y0, t_eval=t_eval,
                            p=peer_rhs.params(base.override({"rod.mu": float(m)})))
            for m in mus]


def peer_accuracy(base, mus, sample) -> dict:
    """The state error over the first second (``bench_peers``: snapshots every 5 ms,
    max(|u − u_ref|∞ / 1 m, |v − v_ref|∞ / V)) against CyRK DOP853 at rtol = atol = 1e-13,
    on the grid points ``sample``: rodjit's at the preset's settings (the preset's
    configuration with t_end = 1 s and a snapshot every 5 ms, its own interval), and for
    each peer method the loosest tolerance of PEER_TOLS whose largest error over the sample
    is at most rodjit's.  Also rodjit's ``radau5`` at the preset's tolerances (context)."""
    import bench_peers

    probs = [bench_peers.Problem("paper-mu100", {"rod.mu": float(mus[i])}) for i in sample]
    refs = [bench_peers.run_cyrk(pb, "DOP853", 1e-13)[1] for pb in probs]

    def rodjit_errors(over: dict) -> list:
        errs = []
        for i, pb, ref in zip(sample, probs, refs):
            r = rodjit.simulate(base.override({
                "rod.mu": float(mus[i]), "time.t_end": bench_peers.T_END,
                "output.snapshot_interval": bench_peers.SNAPSHOT, **over}))
            if not np.allclose(r.t, pb.t_eval, rtol=0, atol=1e-12):
                raise SystemExit("rodjit's snapshot times differ from the peer's")
            errs.append(pb.error(np.vstack([r.u.T, r.v.T]), ref))
        return errs

    own = rodjit_errors({})
    out = {"sample_mu": [float(mus[i]) for i in sample], "rodjit": own,
           "rodjit_radau5": rodjit_errors({"time.integrator": "radau5"}), "peers": {}}
    target = max(own)
    for method in PEER_METHODS:
        ladder = []
        for tol in PEER_TOLS:
            try:
                errs = [pb.error(bench_peers.run_cyrk(pb, method, tol)[1], ref)
                        for pb, ref in zip(probs, refs)]
            except RuntimeError:
                errs = [float("inf")]
            ladder.append((tol, max(errs)))
            if max(errs) <= target:
                out["peers"][method] = {"tol": tol, "errors": errs, "ladder": ladder}
                break
        else:
            out["peers"][method] = {"tol": None, "ladder": ladder}
    return out


def cyrk_pool(problem):
    """A spawned Pool(2) whose workers compile CyRK's right-hand side and solver in their
    initializer (``bench_peers.pool_init``): the pool, the seconds until both were ready
    and each worker's compile time.  Spawned, so that each compiles (a forked worker
    would inherit this process's compiled cfunc)."""
    import multiprocessing as mp

    import bench_peers
    ctx = mp.get_context("spawn")
    ready = ctx.Queue()
    t0 = time.perf_counter()
    pool = ctx.Pool(PEER_JOBS, initializer=bench_peers.pool_init, initargs=(ready, problem))
    compiles = [ready.get(timeout=900)[1] for _ in range(PEER_JOBS)]
    return pool, time.perf_counter() - t0, compiles


def peer_part(base, tmp, repeat: int) -> dict:
    """Part 6 (module docstring)."""
    import bench_peers

    tmp = Path(tmp)
    adopted = adopt_orphans()
    if not adopted:
        print("   (no PR_SET_CHILD_SUBREAPER here: the CPU time is /proc's sampled one)")
    mus = np.linspace(100.0, 300.0, PEER_TIMED)
    sample = np.unique(np.round(np.linspace(0, PEER_TIMED - 1, PEER_SAMPLE)).astype(int))
    t0 = time.perf_counter()
    acc = peer_accuracy(base, mus, sample)
    matching = time.perf_counter() - t0
    methods = {m: r["tol"] for m, r in acc["peers"].items() if r["tol"] is not None}
    problems = peer_problems(base, mus)
    pool, pool_startup, compiles = cyrk_pool(problems[0])
    sizes = (2, *PEER_POINTS)
    runs = {p: [] for p in sizes}
    radau5, pools = [], {m: [] for m in methods}
    try:
        peer_sweep(2, tmp / "peer_warm.h5")          # the kernels in the cache
        peer_sweep(2, tmp / "peer_warm.h5", ("time.integrator=radau5",))
        for _ in range(repeat):                      # in turns: the load hits all alike
            for p in sizes:
                runs[p].append(peer_sweep(p, tmp / f"peer_{p}.h5"))
            radau5.append(peer_sweep(PEER_TIMED, tmp / "peer_radau5.h5",
                                     ("time.integrator=radau5",)))
            for m, tol in methods.items():
                tasks = [(pb, m, tol) for pb in problems]
                t1 = time.perf_counter()
                solved = pool.map(bench_peers.pool_solve, tasks)
                pools[m].append({"wall": time.perf_counter() - t1,
                                 "steps": int(sum(s for _, s in solved))})
    finally:
        pool.terminate()
        pool.join()
    best = {p: min(r, key=lambda x: x["wall"]) for p, r in runs.items()}
    start = best[2]

    def median(f) -> float:
        """The median over the rounds of ``f(k)``: every ratio divides two numbers of the
        same round, whose load the machine's drift changes least."""
        return float(np.median([f(k) for k in range(repeat)]))

    rows, cpu_rows = [], {}
    for p in PEER_POINTS:
        b, r, s2 = best[p], runs[p], runs[2]
        ratio = median(lambda k: r[k]["wall"] / (r[k]["cpu"] / PEER_JOBS + s2[k]["wall"]))
        marginal = median(lambda k: (r[k]["wall"] - s2[k]["wall"])
                          / ((r[k]["cpu"] - s2[k]["cpu"]) / PEER_JOBS))
        # the points' loops run in wall time: what other load takes from the workers shows
        # in them as in the sweep's wall, which CPU time does not see
        loops = median(lambda k: r[k]["wall"] / (r[k]["stepping"] / PEER_JOBS
                                                  + s2[k]["wall"]))
        cpu_rows[p] = {"best": b, "runs": r, "ratio": ratio, "marginal_ratio": marginal,
                       "wall_over_loops_plus_startup": loops}
        rows.append([p, b["wall"], b["cpu"], b["cpu_sampled"], b["stepping"] / PEER_JOBS,
                     start["wall"], ratio, marginal, loops])
    print(f"   rodjit sweep paper-mu100 --grid \"rod.mu=linspace(100,300,P)\" --jobs "
          f"{PEER_JOBS} -q -o F (best of {repeat}, in turns; the ratios the median of the "
          f"rounds'); start-up = the same command "
          f"over 2 points; CPU of all its processes by RUSAGE_CHILDREN"
          f"{' (orphans adopted and reaped)' if adopted else ''}, /proc sampled every 50 ms "
          f"beside it")
    print(_util.table(rows, ["P", "wall [s]", "CPU all [s]", "CPU sampled [s]",
                             "stepping/jobs [s]", "start-up [s]",
                             "wall/(CPU/jobs+start-up)", "marginal wall/(CPU/jobs)",
                             "wall/(loops/jobs+start-up)"]))
    worst = max(r["ratio"] for r in cpu_rows.values())
    print(f"   worst wall / (CPU/jobs + start-up): {worst:.2f} (target <= {TARGET_CPU}: "
          f"{'yes' if worst <= TARGET_CPU else 'NO'}); marginal = (wall − start-up wall) / "
          f"((CPU − start-up CPU)/jobs); loops = the points' run_time (wall time inside "
          f"their compiled loops, where a worker never waits on the sweep): above CPU/jobs "
          f"by what other load on the machine took from the workers")
    own = max(acc["rodjit"])
    print(f"   accuracy over [0, 1 s] on {len(sample)} of the {PEER_TIMED} points (against "
          f"CyRK DOP853 1e-13): rodjit {base.time.integrator} at the preset's rtol "
          f"{base.time.rtol:g}, atol {base.time.atol:g}: {own:.2g}; radau5 at the same "
          f"tolerances {max(acc['rodjit_radau5']):.2g}")
    for m, r in acc["peers"].items():
        if r["tol"] is None:
            print(f"   CyRK {m}: no tolerance down to {PEER_TOLS[-1]:g} reaches it: not timed")
        else:
            print(f"   CyRK {m}: rtol = atol = {r['tol']:.3g} (error {max(r['errors']):.2g})")
    b200, r200, s2 = best[PEER_TIMED], runs[PEER_TIMED], runs[2]
    steady = b200["wall"] - start["wall"]
    loops = b200["stepping"] / PEER_JOBS
    r5 = min(radau5, key=lambda x: x["wall"])
    prow, out_pools = [], {}
    for m, rs in pools.items():
        w = min(x["wall"] for x in rs)
        ratios = {
            "speed_ratio": median(lambda k: rs[k]["wall"] / r200[k]["wall"]),
            "speed_ratio_without_startup": median(
                lambda k: rs[k]["wall"] / (r200[k]["wall"] - s2[k]["wall"])),
            "speed_ratio_loops_alone": median(
                lambda k: rs[k]["wall"] / (r200[k]["stepping"] / PEER_JOBS)),
            "speed_ratio_pool_startup_included": median(
                lambda k: (rs[k]["wall"] + pool_startup) / r200[k]["wall"]),
            "speed_ratio_radau5": median(lambda k: rs[k]["wall"] / radau5[k]["wall"]),
            "speed_ratio_radau5_without_startup": median(
                lambda k: rs[k]["wall"] / (radau5[k]["wall"] - s2[k]["wall"]))}
        out_pools[m] = {"tol": methods[m], "wall": w, "runs": rs, "steps": rs[0]["steps"],
                        **ratios}
        prow.append([f"CyRK {m} {methods[m]:.3g}", w, rs[0]["steps"], b200["wall"], steady,
                     loops, *list(ratios.values())[:4]])
    print(f"   {PEER_TIMED} points over t_end = {base.time.t_end:g} s, {PEER_JOBS} processes "
          f"each: CyRK's spawned Pool({PEER_JOBS}).map (t_eval every {PEER_T_EVAL:g} s, "
          f"returning each point's final state), ready in {pool_startup:.1f} s (compile "
          f"{', '.join(f'{c:.1f}' for c in compiles)} s in its workers, apart), against "
          f"rodjit's sweep as the user meets it and without its start-up; steps: rodjit "
          f"{b200['steps']}")
    print(_util.table(prow, ["peer", "pool [s]", "steps", "rodjit wall [s]",
                             "rodjit − start-up [s]", "rodjit loops/jobs [s]",
                             "rodjit/peer speed", "without start-up", "loops alone",
                             "peer's start-up too"]))
    fastest = min(out_pools, key=lambda m: out_pools[m]["wall"]) if out_pools else None
    if fastest:
        ratio = out_pools[fastest]["speed_ratio"]
        print(f"   rodjit speed / CyRK {fastest} pool speed: {ratio:.2f} (target >= "
              f"{TARGET_PEER}: {'yes' if ratio >= TARGET_PEER else 'NO'}); "
              f"{out_pools[fastest]['speed_ratio_without_startup']:.2f} without the start-up,"
              f" {out_pools[fastest]['speed_ratio_loops_alone']:.2f} for the points' compiled "
              f"loops alone (their run_time over the jobs); medians of the rounds")
        print(f"   (context) the same sweep with --set time.integrator=radau5: {r5['wall']:.2f} s"
              f" wall, {r5['steps']} steps, loops/jobs {r5['stepping'] / PEER_JOBS:.3f} s: "
              f"speed over CyRK {fastest}'s pool "
              f"{out_pools[fastest]['speed_ratio_radau5']:.2f} "
              f"({out_pools[fastest]['speed_ratio_radau5_without_startup']:.2f} without the "
              f"start-up)")
    return {"jobs": PEER_JOBS, "repeat": repeat, "adopted_orphans": adopted,
            "startup": start, "startup_runs": runs[2], "radau5_runs": radau5,
            "cpu": {str(k): v for k, v in cpu_rows.items()},
            "meets_cpu_target": worst <= TARGET_CPU, "accuracy": acc,
            "tolerance_matching": matching, "peer_t_eval": PEER_T_EVAL,
            "pool_startup": pool_startup, "pool_compiles": compiles, "pools": out_pools,
            "fastest_peer": fastest, "rodjit_radau5": r5,
            "meets_peer_target": bool(fastest) and
            out_pools[fastest]["speed_ratio"] >= TARGET_PEER}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="one repetition, no Dask")
    ap.add_argument("--grid-points", type=int, default=2000,
                    help="points of part 4's grid (a multiple of 10; default 2000)")
    ap.add_argument("--baseline", default=None,
                    help="a checkout of another rodjit to run part 4's sweep against")
    ap.add_argument("--engine", action="store_true",
                    help="only part 5: the ensemble engine against the per-point path")
    ap.add_argument("--full", action="store_true",
                    help="part 5: also the per-point path of the 20000 points")
    ap.add_argument("--threads", action="store_true",
                    help="part 5: only threads over batches against processes")
    ap.add_argument("--only-extras", action="store_true",
                    help="part 5: only --baseline and --memory, not the engine's timings")
    ap.add_argument("--memory", action="store_true",
                    help="part 5: the peak memory of the 20000-point sweep")
    ap.add_argument("--diffrax", action="store_true",
                    help="part 5: only the diffrax jit(vmap) row")
    ap.add_argument("--diffrax-points", type=int, default=DIFFRAX_POINTS,
                    help=f"points diffrax is timed on (default {DIFFRAX_POINTS}; 0: all 2000)")
    ap.add_argument("--peer", action="store_true",
                    help="only part 6: the sweep's wall against its CPU, and against "
                         "CyRK's process pool at matched accuracy")
    args = ap.parse_args(argv)
    if args.peer:
        _util.header("parameter sweeps: wall against CPU, and CyRK's process pool")
        with tempfile.TemporaryDirectory() as tmp:
            out = peer_part(load_preset("paper-mu100"), tmp, args.repeat)
        path = _util.save("sweep_peer", out)
        print(f"   -> {path}")
        return out
    if args.diffrax_points < 0:
        ap.error("--diffrax-points must be >= 0")
    if args.diffrax:
        _util.header("parameter sweeps: diffrax jit(vmap) on the CPU")
        base = load_preset("paper-mu100")
        out = diffrax_part(base, args.diffrax_points)
        path = _util.save("sweep_diffrax", out)
        print(f"   -> {path}")
        return out
    if args.engine:
        _util.header("parameter sweeps: the ensemble engine")
        base = load_preset("paper-mu100")
        with tempfile.TemporaryDirectory() as tmp:
            rodjit.sweep(base, {"rod.mu": [0.0]}, scheduler="inline")   # kernels cached
            if args.threads:
                out = {"threads": threads_part(base)}
            elif args.only_extras:
                out = {}
            else:
                out = engine_part(base, tmp, args.full)
                out["diffrax"] = diffrax_part(base, args.diffrax_points)
            here = str(Path(__file__).resolve().parents[1])
            if args.baseline:
                out["baseline"] = baseline_part(here, args.baseline, tmp, args.repeat)
                out["baseline_loop"] = loop_pairs(here, args.baseline, 2 * args.repeat)
            if args.memory:
                m = peak_memory(here, big_grid(2000), Path(tmp) / "memory.h5", 2)
                print(f"   20000 points, 2 jobs, CLI: peak resident memory of the sweep and its "
                      f"workers {m['peak_bytes'] / 2**20:.0f} MiB (target < 1024 MiB), wall "
                      f"{m['wall']:.1f} s")
                out["memory"] = m
        name = ("sweep_threads" if args.threads else "sweep_extras" if args.only_extras
                else "sweep_engine")
        path = _util.save(name, {str(k): v for k, v in out.items()})
        print(f"   -> {path}")
        return out
    if args.grid_points < 10 or args.grid_points % 10:
        ap.error("--grid-points must be a positive multiple of 10")
    repeat = 1 if args.quick else args.repeat
    _util.header("parameter sweeps: scaling, Dask, overhead per point")
    base = load_preset("paper-mu100")
    small = base.override({"time.t_end": 0.02})
    cases = {"1 job": {"jobs": 1}, "2 jobs": {"jobs": 2}}
    try:
        import distributed  # noqa: F401
        if not args.quick:
            cases["dask 2 workers"] = {"jobs": 2, "scheduler": "local"}
            cases["dask 1 worker"] = {"jobs": 1, "scheduler": "local"}
    except ImportError:
        print("   (distributed not installed: no Dask row)")
    results = {name: [] for name in cases}
    small_runs = {"1 job": [], "2 jobs": []}
    with tempfile.TemporaryDirectory() as tmp:
        rodjit.sweep(base, {"rod.mu": [0.0]}, scheduler="inline")      # kernels in the cache
        for _ in range(repeat):
            for name, kw in cases.items():
                results[name].append(timed_sweep(base, GRID, tmp, **kw))
            for name, jobs in (("1 job", 1), ("2 jobs", 2)):
                small_runs[name].append(timed_sweep(small, SMALL_GRID, tmp, jobs=jobs))
        bound = stepping_bound(base, big_grid(args.grid_points // 10), tmp, repeat,
                               args.baseline)
    best = {name: best_of(r) for name, r in results.items()}
    one, two = best["1 job"], best["2 jobs"]
    scaling = two["points_per_second"] / one["points_per_second"]
    scaling_e2e = two["points_per_second_end_to_end"] / one["points_per_second_end_to_end"]
    rows = []
    for name, r in best.items():
        rows.append([name, r["backend"], r["points"], r["startup"], r["steady"],
                     r["teardown"], r["points_per_second"], r["points_per_second_end_to_end"],
                     1e3 * r["point_wall_mean"]])
    print(_util.table(rows, ["64-point grid", "backend", "points", "start-up [s]",
                             "steady [s]", "teardown [s]", "points/s", "points/s end-to-end",
                             "point mean [ms]"]))
    print(f"   2 jobs / 1 job: {scaling:.2f}x steady state (target >= {TARGET_SCALING}x: "
          f"{'yes' if scaling >= TARGET_SCALING else 'NO'}), {scaling_e2e:.2f}x end to end "
          f"(start-up included)")
    out = {"grid": GRID, "base": "paper-mu100", "repeat": repeat, "runs": results,
           "scaling": scaling, "scaling_end_to_end": scaling_e2e,
           "meets_scaling_target": scaling >= TARGET_SCALING}
    if "dask 2 workers" in best:
        d = best["dask 2 workers"]
        over = d["steady"] / two["steady"] - 1
        over_e2e = d["wall"] / two["wall"] - 1
        print(f"   Dask LocalCluster vs pool, 2 workers: {100 * over:+.1f}% steady state (target "
              f"< {100 * TARGET_DASK:g}%: {'yes' if over < TARGET_DASK else 'NO'}), "
              f"{100 * over_e2e:+.1f}% end to end (cluster start-up {d['startup']:.2f} s vs "
              f"pool {two['startup']:.2f} s)")
        out.update(dask_overhead=over, dask_overhead_end_to_end=over_e2e,
                   meets_dask_target=over < TARGET_DASK)
        d1 = best["dask 1 worker"]
        over1 = d1["steady"] / one["steady"] - 1
        print(f"   (context) 1 worker each, a core left for Dask's scheduler and nannies: "
              f"{100 * over1:+.1f}% steady state")
        out["dask_overhead_one_worker"] = over1
    rows = []
    for name, runs in small_runs.items():
        r = best_of(runs)
        rows.append([name, r["points"], r["steady"], r["points_per_second"],
                     1e3 * r["point_run_mean"], 1e3 * r["setup_in_worker"],
                     1e3 * r["overhead_per_point"]])
        out[f"small_{name.replace(' ', '_')}"] = r
    print(_util.table(rows, ["N = 5, t_end = 0.02", "points", "steady [s]", "points/s",
                             "stepping [ms]", "set-up in worker [ms]",
                             "overhead/point [ms]"]))
    over = best_of(small_runs["1 job"])["overhead_per_point"]
    print(f"   overhead per point, 1 job: {1e3 * over:.2f} ms (target < "
          f"{1e3 * TARGET_OVERHEAD:g} ms: {'yes' if over < TARGET_OVERHEAD else 'NO'})")
    out["overhead_per_point"] = over
    out["meets_overhead_target"] = over < TARGET_OVERHEAD
    print_stepping_bound(bound)
    out["stepping_bound"] = bound
    out["meets_stepping_target"] = bound["wall_over_stepping"] <= TARGET_STEPPING
    path = _util.save("sweep", out)
    print(f"   -> {path}")
    return out


if __name__ == "__main__":
    main()
