"""Explicit step throughput against the C speed limit, at N = 1000 (target ≤ 1.25×) and over N.

The anchor ``limit.c`` (vendored beside this script) is compiled with ``gcc -O3 -march=native``
and run here, interleaved with rodjit, so both see the same machine load; each figure is
the best of ``--repeat`` runs, and every ratio divides two numbers from this run.

Same problem on both sides: κ = 100, g = −1, κ_b = 100, β = 0.05, the rod at rest with its
bottom at 0.5, steps of dt = 0.5 h/11.18 (≈ cfl 0.5 of the stability limit).  The C loop is
a bare fused velocity-Verlet with a fixed step and μ = 0.  rodjit is measured through its
real stepping path, ``Run`` / ``rodjit.simulate`` → the compiled ``advance`` (event
tracking, admissibility checks and stiffness bound every step, output landing).

First table, N = 1000, 20 000 steps (the rod falls without touching the floor), outputs
rare (t0 and t_end only), ``time.control = "cfl"``:

* ``fixed``: time.dt = the C step (like for like);
* ``adaptive``: time.cfl = 0.5, the step from the stiffness bound every step (≈ the C step);
* ``adaptive, default cfl``: time.cfl = 0.05, the default (same work per step);
* context rows, not the target: the bare ``verlet.step`` in a compiled loop (no loop
  bookkeeping), a bouncing run (contact and events), and γ = 1e-3 against ``limit`` with γ.

Second table, over N = 100, 1000 and 10 000: a user's fixed-step run, ``verlet`` and
``semi-implicit`` with time.dt = the C step, 20 000 steps, a snapshot every 5000 steps and
a diagnostics row every 1000, and ``time.control`` left at its default (``tolerance``,
which under fixed steps chooses nothing); against the C loop at the same N and steps
(at N = 100 the 8.9 s run bounces on the floor, on both sides; at μ = γ = 0 the two rodjit
schemes do the C loop's work, ``semi-implicit`` without the bending term).  The target
applies at N = 1000.

    python benchmarks/bench_explicit.py [--repeat 7] [--quick]
"""
from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numba

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _util  # noqa: E402

import rodjit  # noqa: E402
from rodjit.stepping.integrators import kdk as verlet  # noqa: E402  (the Verlet row of the stage table)
from rodjit.stepping.integrators.kdk import Verlet  # noqa: E402

try:      # rodjit's own options (no reference counting), without the disk cache
    from rodjit._jit import JIT_OPTIONS, load_numba
    load_numba()
    _BARE_OPTIONS = {k: v for k, v in JIT_OPTIONS.items() if k != "cache"}
except ImportError:
    _BARE_OPTIONS = {}

N = 1000
STEPS = 20_000
C_WAVE = 11.18                      # limit.c's wave-speed constant: dt = 0.5 h / 11.18
TARGET = 1.25
SCALING_N = (100, 1000, 10_000)
SCALING_SCHEMES = ("verlet", "semi-implicit")


def base_config(steps=STEPS, gamma=0.0, n=None):
    n = N if n is None else n
    h = 1.0 / n
    dt = 0.5 * h / C_WAVE
    if gamma > 0:
        dt = min(dt, 0.25 * h * h / gamma ** 0.5)
    t_end = steps * dt
    cfg = rodjit.Config().override({
        "rod.N": n, "rod.kappa": 100.0, "rod.gamma": gamma, "floor.kappa_b": 100.0,
        "floor.beta": 0.05, "gravity.g": -1.0, "initial.height": 0.5,
        "time.t_end": t_end, "time.integrator": "verlet", "time.control": "cfl",
        "output.snapshot_interval": t_end,
        "output.diagnostics_interval": 0.0})
    return cfg, dt


def rodjit_run(cfg):
    """ns per node-step of the compiled stepping (compile time excluded) and the result."""
    res = rodjit.simulate(cfg)
    st = res.stats
    return st["run_time"] * 1e9 / (st["steps"] * (cfg.rod.N + 1)), res


@numba.njit(**_BARE_OPTIONS)   # not cached: compiled against whichever rodjit is imported
def _bare_loop(scheme, system, rod, floor, state, trial, work, sstats, dt, pairs):
    u, v, a = state[0], state[1], state[2]
    u2, v2, a2 = trial[0], trial[1], trial[2]
    bad = 0
    for _ in range(pairs):
        r = verlet.step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt)
        bad += r[0]
        r = verlet.step(scheme, system, rod, floor, u2, v2, a2, u, v, a, work, sstats, dt)
        bad += r[0]
    return bad


def fixed_config(n, integrator, steps):
    """The second table's run: a fixed-step ``integrator`` run at N = n (module docstring),
    and its step."""
    cfg, dt = base_config(steps, n=n)
    return cfg.override({
        "time.integrator": integrator, "time.dt": dt, "time.control": rodjit.Config().time.control,
        "output.snapshot_interval": (steps // 4) * dt,
        "output.diagnostics_interval": (steps // 20) * dt}), dt


def bare_step(cfg, dt, steps):
    """ns per node-step of verlet.step alone, called back to back in a compiled loop."""
    from rodjit.driver.run import Run
    import time
    run = Run(cfg)
    a = run.arrays
    verlet.initial(run.scheme, run.system, run.rod, run.floor, a.state[0], a.state[1],
                   a.state[2], a.work)
    args = (Verlet(run.scheme.cfl), run.system, run.rod, run.floor, a.state.copy(),
            a.trial.copy(), a.work, a.sstats, dt)
    _bare_loop(*args, 1)                           # compile (or load) outside the timing
    t0 = time.perf_counter()
    bad = _bare_loop(*args, steps // 2)
    elapsed = time.perf_counter() - t0
    assert bad == 0
    return elapsed * 1e9 / ((steps // 2) * 2 * (cfg.rod.N + 1))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7, help="repetitions (best is kept)")
    ap.add_argument("--quick", action="store_true", help="fewer steps and repetitions")
    args = ap.parse_args(argv)
    steps = 4000 if args.quick else STEPS
    repeat = 3 if args.quick else args.repeat

    _util.header("explicit step throughput, N = 1000 and over N, vs C (limit.c)")
    cfg, dt = base_config(steps)
    cfg_g, dt_g = base_config(steps // 4, gamma=1e-3)
    variants = {
        "fixed": cfg.override({"time.dt": dt}),
        "adaptive": cfg.override({"time.cfl": 0.5, "time.control": "cfl"}),
        "adaptive, default cfl": cfg.override({"time.cfl": 0.05, "time.control": "cfl",
                                               "time.t_end": cfg.time.t_end / 10}),
        "bouncing (contact, events)": cfg.override({
            "time.cfl": 0.5, "time.control": "cfl", "initial.height": 0.02, "initial.velocity": -1.0,
            "floor.kappa_b": 1000.0, "time.t_end": 4 * cfg.time.t_end}),
        "gamma=1e-3, fixed": cfg_g.override({"time.dt": dt_g}),
    }
    scaling = {(n, name): fixed_config(n, name, steps)[0]
               for n in SCALING_N for name in SCALING_SCHEMES}
    with tempfile.TemporaryDirectory() as tmp:
        c = _util.build_limit(Path(tmp))
        # warm up: compile or load every kernel, check the runs
        for v in [*variants.values(), *scaling.values()]:
            _, res = rodjit_run(v.override({"time.t_end": v.time.t_end / 20}))
        _, res = rodjit_run(variants["fixed"])
        assert res.stats["steps"] == steps and res.u_final[0] > 0 and res.episodes["t_start"].size == 0
        _, res = rodjit_run(variants["bouncing (contact, events)"])
        bounce_info = {"episodes": int(res.episodes["t_start"].size), "bounces": res.n_bounces}
        for (n, name), v in scaling.items():
            _, res = rodjit_run(v)
            assert res.stats["steps"] == steps and res.stats["rejected_steps"] == 0, (n, name)
            assert len(res.t) == 5 and len(res.diagnostics["t"]) == 21, (n, name)
        times = {k: [] for k in ["C", "C gamma=1e-3", "bare verlet.step", *variants]}
        times.update({_scaling_key(n, name): [] for n, name in scaling})
        times.update({f"C N={n}": [] for n in SCALING_N})
        for _ in range(repeat):
            times["C"].append(_util.run_limit(c["exe"], N, steps)["ns_per_node_step"])
            times["C gamma=1e-3"].append(
                _util.run_limit(c["exe"], N, steps // 4, 1e-3)["ns_per_node_step"])
            for name, v in variants.items():
                times[name].append(rodjit_run(v)[0])
            times["bare verlet.step"].append(bare_step(variants["fixed"], dt, steps))
            for n in SCALING_N:
                times[f"C N={n}"].append(_util.run_limit(c["exe"], n, steps)["ns_per_node_step"])
                for name in SCALING_SCHEMES:
                    times[_scaling_key(n, name)].append(rodjit_run(scaling[n, name])[0])
    best = {k: _util.best(v) for k, v in times.items()}
    rows = []
    spec = [("fixed", "C", True), ("adaptive", "C", True), ("adaptive, default cfl", "C", True),
            ("bare verlet.step", "C", False), ("bouncing (contact, events)", "C", False),
            ("gamma=1e-3, fixed", "C gamma=1e-3", False)]
    results = []

    def row(name, ref, is_target, label):
        ratio = best[name] / best[ref]
        ok = ("yes" if ratio <= TARGET else "NO") if is_target else "(context)"
        results.append({"variant": name, "ns_per_node_step": best[name], "reference": ref,
                        "reference_ns_per_node_step": best[ref], "ratio": ratio,
                        "target": TARGET if is_target else None,
                        "meets_target": (ratio <= TARGET) if is_target else None})
        return [label, best[name], ref, best[ref], ratio, f"<= {TARGET}" if is_target else "-", ok]

    headers = ["rodjit path", "ns/node-step", "vs", "C ns/node-step", "ratio", "target", "met"]
    rows = [row(name, ref, is_target, f"rodjit {name}") for name, ref, is_target in spec]
    print(_util.table(rows, headers))
    print(f"\n   fixed steps over N ({steps} steps, a snapshot every {steps // 4}, diagnostics"
          f" every {steps // 20}, time.control = {rodjit.Config().time.control!r}):")
    rows = [row(_scaling_key(n, name), f"C N={n}", n == N and name == "verlet",
                f"{name}, N = {n}") for n in SCALING_N for name in SCALING_SCHEMES]
    print(_util.table(rows, headers))
    print(f"   best of {repeat}; C: {c['compiler']} {c['flags']} ({c['source']})")
    path = _util.save("explicit", {
        "n": N, "steps": steps, "dt": dt, "repeat": repeat, "c": {k: c[k] for k in c if k != "exe"},
        "scaling_n": list(SCALING_N), "bouncing_run": bounce_info, "results": results,
        "all_times_ns_per_node_step": times})
    print(f"   -> {path}")
    return results


def _scaling_key(n, name):
    return f"{name} fixed, N={n}"


if __name__ == "__main__":
    main()
